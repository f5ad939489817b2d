"""Check that `rocc grammar --format lark` loads in Python `lark` and parses scenario files.

Usage: python3 check_lark.py GRAMMAR.lark [FILE.scn ...]
Exits non-zero with a message on the first failure; prints `ok N` otherwise.
Needs the `lark` PyPI package only.
"""

import sys

import lark


def main():
    with open(sys.argv[1], encoding="utf-8") as f:
        grammar = f.read()
    # Earley with the dynamic lexer: the export is character level (no %ignore, no tokens).
    parser = lark.Lark(grammar, start="start", parser="earley", lexer="dynamic")
    n = 0
    for path in sys.argv[2:]:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        try:
            parser.parse(text)
        except lark.exceptions.LarkError as e:
            sys.exit(f"{path}: the lark export rejects it: {e}")
        n += 1
    print(f"ok {n}")


if __name__ == "__main__":
    main()
