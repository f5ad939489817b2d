//! Edit requests as the command line writes them: `KIND at X,Y yaw A`, `AGENT`, `AGENT by DX,DY`.

use crate::diag::Diagnostic;

/// One box edit. Coordinates are metres; for a compiled clip they are in the ego frame of the
/// first edited frame and fixed in the world from there, for a `.scn` in its world frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    Insert { kind: String, x: f64, y: f64, yaw: f64 },
    Delete { agent: String },
    Move { agent: String, dx: f64, dy: f64 },
}

impl Edit {
    /// As recorded in the manifest.
    pub fn describe(&self) -> String {
        match self {
            // Degrees read back from radians: rounded so `yaw 30` is recorded as 30, not 29.999999999999996.
            Edit::Insert { kind, x, y, yaw } => {
                format!("insert {kind} at {x},{y} yaw {}deg", (yaw.to_degrees() * 1e9).round() / 1e9)
            }
            Edit::Delete { agent } => format!("delete {agent}"),
            Edit::Move { agent, dx, dy } => format!("move {agent} by {dx},{dy}"),
        }
    }
}

fn bad(op: &str, text: &str, why: &str) -> Diagnostic {
    let form = match op {
        "insert" => {
            "--insert KIND at X,Y yaw A   (e.g. `--insert sedan at 12,-3.5 yaw 90`; A in degrees, or `1.57rad`)"
        }
        "move" => "--move AGENT by DX,DY        (e.g. `--move car_2 by 0,3.5`)",
        _ => "--delete AGENT",
    };
    Diagnostic::error("E0717", format!("`--{op} {text}`: {why}")).help(format!("write {form}"))
}

fn pair(op: &str, text: &str, s: &str) -> Result<(f64, f64), Diagnostic> {
    let (a, b) = s.split_once(',').ok_or_else(|| bad(op, text, &format!("`{s}` is not X,Y")))?;
    let n = |v: &str| {
        v.trim()
            .trim_end_matches('m')
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(op, text, &format!("`{}` is not a number", v.trim())))
    };
    Ok((n(a)?, n(b)?))
}

/// Parse one edit; `op` is `insert`, `delete` or `move`, `words` its arguments.
pub fn parse_edit(op: &str, words: &[String]) -> Result<Edit, Diagnostic> {
    let text = words.join(" ");
    // `12, -3.5` and `12,-3.5` both read as one pair.
    let joined = text.replace(", ", ",").replace(" ,", ",");
    let w: Vec<&str> = joined.split_whitespace().collect();
    let ident = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    match op {
        "insert" => {
            let [kind, at, xy, rest @ ..] = w.as_slice() else {
                return Err(bad(op, &text, "expected a kind, `at` and a position"));
            };
            if *at != "at" || !ident(kind) {
                return Err(bad(op, &text, "expected `KIND at X,Y`"));
            }
            let (x, y) = pair(op, &text, xy)?;
            let yaw = match rest {
                [] => 0.0,
                ["yaw", a] => {
                    let (v, rad) = match a.strip_suffix("rad") {
                        Some(v) => (v, true),
                        None => (a.trim_end_matches("deg"), false),
                    };
                    let v: f64 = v
                        .parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| bad(op, &text, &format!("`{a}` is not an angle")))?;
                    if rad { v } else { v.to_radians() }
                }
                _ => return Err(bad(op, &text, "expected `yaw A` after the position")),
            };
            Ok(Edit::Insert { kind: kind.to_string(), x, y, yaw })
        }
        "delete" => match w.as_slice() {
            [a] if ident(a) => Ok(Edit::Delete { agent: a.to_string() }),
            _ => Err(bad(op, &text, "expected one agent name")),
        },
        "move" => match w.as_slice() {
            [a, "by", d] if ident(a) => {
                let (dx, dy) = pair(op, &text, d)?;
                Ok(Edit::Move { agent: a.to_string(), dx, dy })
            }
            _ => Err(bad(op, &text, "expected `AGENT by DX,DY`")),
        },
        _ => Err(bad(op, &text, "unknown edit")),
    }
}
