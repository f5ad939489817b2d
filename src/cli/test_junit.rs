//! `rocc test --junit FILE`: the results as JUnit XML, the format CI services read.

/// One test case: `class` is the scenario file, `failure` the text shown when it failed.
pub struct Case {
    pub class: String,
    pub name: String,
    pub failure: Option<String>,
}

pub fn xml(cases: &[Case]) -> String {
    let failures = cases.iter().filter(|c| c.failure.is_some()).count();
    let mut out = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n<testsuite name=\"rocc test\" tests=\"{}\" failures=\"{failures}\">\n",
        cases.len()
    );
    for c in cases {
        out.push_str(&format!("  <testcase classname=\"{}\" name=\"{}\"", esc(&c.class), esc(&c.name)));
        match &c.failure {
            None => out.push_str("/>\n"),
            Some(f) => {
                let first = f.lines().next().unwrap_or("");
                out.push_str(&format!(
                    ">\n    <failure message=\"{}\">{}</failure>\n  </testcase>\n",
                    esc(first),
                    esc(f)
                ));
            }
        }
    }
    out.push_str("</testsuite>\n</testsuites>\n");
    out
}

fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            // XML 1.0 has no escape for other control characters.
            c if c.is_control() && !matches!(c, '\n' | '\t' | '\r') => {}
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn junit_escapes_and_counts_failures() {
        let cases = [
            Case { class: "a.scn".into(), name: "expect gap a with b at_least 2 m".into(), failure: None },
            Case {
                class: "a.scn".into(),
                name: "snapshot".into(),
                failure: Some("E1020 <diff> & \"more\"\u{1b}[0m".into()),
            },
        ];
        let x = xml(&cases);
        assert!(x.contains("tests=\"2\" failures=\"1\""), "{x}");
        assert!(x.contains("E1020 &lt;diff&gt; &amp; &quot;more&quot;[0m"), "{x}");
    }
}
