//! E00xx: files and syntax.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0001",
        title: "syntax error",
        explanation: "The file does not follow the grammar of the `.scn` language. The error points at the\n\
first token the parser could not accept. When a block was left open, it points at the `{` that\n\
is never closed and shows where the next statement begins, or which `}` (indented for an\n\
enclosing block) was taken as the block's end.\n
    agent ego: sedan { at west.in[1], 20 m before center     // `}` missing here
    agent other: sedan { ... }\n\n\
Close every `{` with `}`. Statements are separated by newlines or `;`.",
    },
    Code {
        code: "E0002",
        title: "cannot read file",
        explanation: "A scenario or an imported file could not be read: it does not exist, is a directory,\n\
is not UTF-8 text, or is larger than the 4 MiB rocc accepts for one source file.\n
    use \"kinds/trucks.scn\"      // error when kinds/trucks.scn does not exist
    $ rocc check missing.scn     // error: cannot read `missing.scn`",
    },
    Code {
        code: "E0003",
        title: "import cycle",
        explanation: "`use` imports form a cycle: a file imports itself, directly or through others.\n
    // a.scn\n    use \"b.scn\"\n    // b.scn\n    use \"a.scn\"      // error: cycle a.scn -> b.scn -> a.scn\n\n\
Move the shared kinds into a third file that both import.",
    },
    Code {
        code: "E0004",
        title: "import escapes the project",
        explanation: "`use` paths are relative to the importing file and must stay inside the directory of\n\
the scenario being compiled: absolute paths and paths that climb out with `..` are rejected, so\n\
a scenario library can be moved and compiled anywhere.\n
    use \"kinds/trucks.scn\"      // fine\n    use \"/etc/kinds.scn\"        // error\n    use \"../../kinds.scn\"       // error",
    },
    Code {
        code: "E0005",
        title: "wrong items in a file",
        explanation: "A scenario file holds exactly one `scenario` block (plus `use` and `kind` items); an\n\
imported file holds only `kind` items and further `use` imports.\n
    // kinds.scn, imported with `use \"kinds.scn\"`
    kind forklift: vehicle { length 3 m; width 1.2 m; height 2.1 m }   // fine
    scenario s { ... }                                                        // error",
    },
];
