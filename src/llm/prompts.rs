//! The prompt files under `prompts/` (see prompts/README.md for their format and versioning).

pub struct Prompt {
    pub name: &'static str,
    pub version: &'static str,
    system: &'static str,
    user: &'static str,
}

const SCHEMA: &str = include_str!("../../prompts/schema.md");
const GOALS_JOINT: &str = include_str!("../../prompts/goals_joint.md");
const GOALS_AGENT: &str = include_str!("../../prompts/goals_agent.md");
const REPAIR: &str = include_str!("../../prompts/repair.md");
const DSL: &str = include_str!("../../prompts/dsl.md");

/// Read a prompt file's text (header line, system part, `## user` part).
pub fn load(raw: &'static str) -> Prompt {
    let (header, body) = raw.split_once('\n').expect("a prompt file starts with its header line");
    let tag = header.trim().trim_start_matches("<!--").trim_end_matches("-->").trim();
    let mut words = tag.split_whitespace().skip(2);
    let name = words.next().expect("prompt header: `<!-- rocc prompt NAME vN -->`");
    let version = words.next().expect("prompt header: `<!-- rocc prompt NAME vN -->`");
    let (system, user) = body.split_once("\n## user\n").unwrap_or((body, ""));
    Prompt { name, version, system: system.trim(), user: user.trim() }
}

pub fn schema() -> Prompt {
    load(SCHEMA)
}
pub fn goals_joint() -> Prompt {
    load(GOALS_JOINT)
}
pub fn goals_agent() -> Prompt {
    load(GOALS_AGENT)
}
pub fn repair() -> Prompt {
    load(REPAIR)
}
/// The language reference other prompts include as `{{dsl}}`.
pub fn dsl() -> Prompt {
    load(DSL)
}

/// Every prompt with its version, for transcripts.
pub fn versions() -> Vec<(&'static str, &'static str)> {
    [schema(), goals_joint(), goals_agent(), repair(), dsl()].iter().map(|p| (p.name, p.version)).collect()
}

fn fill(template: &str, vars: &[(&str, &str)]) -> String {
    let mut out = template.to_string();
    for (k, v) in vars {
        out = out.replace(&format!("{{{{{k}}}}}"), v);
    }
    out
}

impl Prompt {
    /// (system, user) messages with the placeholders filled.
    pub fn render(&self, vars: &[(&str, &str)]) -> (String, String) {
        (fill(self.system, vars), fill(self.user, vars))
    }
    pub fn text(&self) -> &'static str {
        self.system
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn every_prompt_has_a_name_a_version_and_a_user_part() {
        for p in [super::schema(), super::goals_joint(), super::goals_agent(), super::repair()] {
            assert!(p.version.starts_with('v'), "{}", p.name);
            assert!(!p.user.is_empty(), "{} has no `## user` part", p.name);
        }
        assert_eq!(super::dsl().name, "dsl");
    }
}
