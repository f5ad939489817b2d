//! Edits on a `.scn` file: the text is changed where the AST says (spans), and the result is
//! gated by the checker and the placement pass, whose E02xx diagnostics say why an insertion or
//! a move is rejected (off its surface, overlapping). Coordinates are in the scenario's world.

use super::{Edit, kind_info};
use crate::diag::{Diagnostic, did_you_mean};
use crate::source::{SourceMap, Span};
use crate::syntax::ast;
use std::path::Path;

fn metres(v: &ast::Value) -> Option<f64> {
    if v.hi.is_some() {
        return None;
    }
    let f = match v.unit.as_ref().map(|u| u.text.as_str()) {
        None | Some("m") => 1.0,
        Some("cm") => 0.01,
        Some("km") => 1000.0,
        _ => return None,
    };
    Some(v.lo.value * f)
}

fn num(v: f64) -> String {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 { "0".into() } else { format!("{r}") }
}

/// Apply `edits` to the text of `path` in order; returns the edited text once it checks and
/// places. `sources` receives the edited text so diagnostics point into it.
pub fn edit_scn(path: &Path, edits: &[Edit], sources: &mut SourceMap) -> Result<String, Vec<Diagnostic>> {
    let mut text = crate::check::load::read_source(path)
        .map_err(|m| vec![Diagnostic::error("E0002", m).help("pass a readable `.scn` file")])?;
    let base = path.parent().unwrap_or(Path::new("."));
    for e in edits {
        let mut scratch = SourceMap::default();
        let id = scratch.add(path.display().to_string(), text.clone());
        let file = crate::syntax::parse(id, &text).map_err(|d| vec![d])?;
        let Some(sc) = file.items.iter().find_map(|i| match i {
            ast::Item::Scenario(s) => Some(s),
            _ => None,
        }) else {
            return Err(vec![
                Diagnostic::error("E0714", format!("`{}` declares no scenario", path.display()))
                    .help("edit a file with a `scenario` block"),
            ]);
        };
        let agents: Vec<&ast::Agent> = sc
            .stmts
            .iter()
            .filter_map(|s| match s {
                ast::ScenarioStmt::Agent(a) => Some(a),
                _ => None,
            })
            .collect();
        let find = |name: &str| -> Result<&ast::Agent, Vec<Diagnostic>> {
            agents.iter().copied().find(|a| a.name.name == name).ok_or_else(|| {
                let names: Vec<&str> = agents.iter().map(|a| a.name.name.as_str()).collect();
                vec![
                    Diagnostic::error(
                        "E0709",
                        format!("{}: no agent `{name}` in scenario `{}`", e.describe(), sc.name.name),
                    )
                    .help(did_you_mean(name, &names, "agent")),
                ]
            })
        };
        // (span to replace, replacement), applied back to front.
        let mut splices: Vec<(Span, String)> = Vec::new();
        match e {
            Edit::Insert { kind, x, y, yaw } => {
                kind_info(kind).map_err(|d| vec![d])?;
                let mut k = 1;
                let name = loop {
                    let n = format!("inserted_{kind}_{k}");
                    if agents.iter().all(|a| a.name.name != n) {
                        break n;
                    }
                    k += 1;
                };
                let end = sc.span.end.saturating_sub(1);
                splices.push((
                    Span { file: id, start: end, end },
                    format!(
                        "\n    agent {name}: {kind} {{ at ({} m, {} m) heading {} deg }}\n",
                        num(*x),
                        num(*y),
                        num(yaw.to_degrees())
                    ),
                ));
            }
            Edit::Delete { agent } => {
                let a = find(agent)?;
                // Take the line's indentation with it.
                let cut = |span: Span| {
                    let bytes = text.as_bytes();
                    let mut start = span.start as usize;
                    while start > 0 && (bytes[start - 1] == b' ' || bytes[start - 1] == b'\t') {
                        start -= 1;
                    }
                    (Span { file: id, start: start as u32, end: span.end }, String::new())
                };
                splices.push(cut(a.span));
                // The `expect` lines about the agent go with it: they are about a scene that no
                // longer is.
                for st in &sc.stmts {
                    if let ast::ScenarioStmt::Expect(b) = st {
                        let about = b.items.iter().filter(|x| x.agents().iter().any(|n| n.name == *agent));
                        splices.extend(about.map(|x| cut(x.span)));
                    }
                }
            }
            Edit::Move { agent, dx, dy } => {
                let a = find(agent)?;
                let cannot = |why: &str| {
                    vec![Diagnostic::error("E0714", format!("{}: `{agent}` {why}", e.describe()))
                        .label(a.span, "this agent")
                        .help("only agents placed at `(X m, Y m)` or replaying a `track` move by DX,DY; for a lane placement change its distance or `offset`")]
                };
                let mut moved = false;
                for st in &a.stmts {
                    match st {
                        ast::AgentStmt::At { place: ast::Placement::World { x, y, .. }, .. } => {
                            let (Some(xv), Some(yv)) = (metres(x), metres(y)) else {
                                return Err(cannot("is placed with ranges or units other than m"));
                            };
                            splices.push((x.span, format!("{} m", num(xv + dx))));
                            splices.push((y.span, format!("{} m", num(yv + dy))));
                            moved = true;
                        }
                        ast::AgentStmt::Track(t) => {
                            for kf in &t.keys {
                                let ast::KeyPose::World { x, y, .. } = &kf.pose else {
                                    return Err(cannot("has a keyframe placed relative to the road"));
                                };
                                let (Some(xv), Some(yv)) = (metres(x), metres(y)) else {
                                    return Err(cannot("has a keyframe with a range or an unusual unit"));
                                };
                                splices.push((x.span, format!("{} m", num(xv + dx))));
                                splices.push((y.span, format!("{} m", num(yv + dy))));
                            }
                            moved = true;
                        }
                        _ => {}
                    }
                }
                if !moved {
                    return Err(cannot("is placed relative to the road"));
                }
            }
        }
        splices.sort_by_key(|(s, _)| std::cmp::Reverse(s.start));
        for (s, r) in splices {
            text.replace_range(s.start as usize..s.end as usize, &r);
        }
    }
    // The gate: the edited scene must check and place (surfaces, overlaps) like any other.
    let scen = crate::check::check_text(&path.display().to_string(), &text, base, sources)?;
    crate::compile::front(scen, None)?;
    Ok(text)
}
