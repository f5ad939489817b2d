//! `rocc text` and the rare-scene vocabulary: canned model replies (an in-process fake server,
//! no model) that use postures, behaviour settings, triggers, goal phases, sirens, lamps and doors each yield a
//! scenario that checks; the goal grammars admit triggers and phases; the grammar export has
//! the new rules.

#[path = "llm_support/fake.rs"]
mod fake;
#[path = "llm_support/gbnf.rs"]
mod gbnf;

use fake::{chat, serve};
use rocc::llm::client::{ClientConfig, Server};
use rocc::llm::schema::Overrides;
use rocc::llm::{self, Outcome, Plan};
use serde_json::{Value, json};
use std::time::Duration;

fn opts(url: &str, plan: Plan) -> llm::Options {
    llm::Options {
        client: ClientConfig {
            endpoint: url.to_string(),
            model: "test-model".into(),
            api_key: None,
            server: Server::Vllm,
            timeout: Duration::from_secs(5),
            retries: 0,
            backoff: Duration::from_millis(5),
            max_tokens: 512,
            temperature: 0.0,
            seed: 0,
        },
        plan,
        max_repairs: 0,
        overrides: Overrides::default(),
        constrain: true,
        image: None,
    }
}

/// The scene written from a schema reply and a goal reply, which must check first time (no
/// repair rounds are allowed).
fn accepted(schema: &Value, goals: &[&str], plan: Plan) -> String {
    let mut replies = vec![chat(&schema.to_string())];
    replies.extend(goals.iter().map(|g| chat(g)));
    let fake = serve(replies);
    let (out, r) = llm::text_to_scenario("a rare scene", &opts(&fake.url, plan), "scene.scn", &std::env::temp_dir());
    match out {
        Outcome::Accepted { text } => {
            assert_eq!(r.attempts.len(), 1, "{:?}", r.attempts);
            text
        }
        Outcome::Rejected { text, diags, .. } => {
            panic!("{text}\n{:?}", diags.iter().map(|d| (d.code, d.message.clone())).collect::<Vec<_>>())
        }
        Outcome::Failed(d) => panic!("{}: {}", d.code, d.message),
    }
}

fn lane(name: &str, kind: &str, arm: &str, dir: &str, dist: f64, speed: f64) -> Value {
    json!({"name": name, "kind": kind, "on": "lane", "arm": arm, "direction": dir, "lane": 1,
        "distance_m": dist, "relation": "before", "landmark": "center", "speed_kmh": speed, "ego": name == "ego"})
}

fn sidewalk(name: &str, dist: f64) -> Value {
    json!({"name": name, "kind": "child", "on": "sidewalk", "arm": "east", "direction": "out", "lane": 1,
        "distance_m": dist, "relation": "after", "landmark": "center", "speed_kmh": 0, "ego": false})
}

fn straight(agents: Vec<Value>) -> Value {
    json!({"name": "rare", "brief": "a rare scene", "duration_s": 6,
        "road": {"template": "straight", "lanes": 1, "speed_limit_kmh": 50, "sidewalks": true},
        "agents": agents})
}

#[test]
fn postures_behaviour_triggers_and_phases_from_the_model_check() {
    let mut ego = lane("ego", "sedan", "west", "in", 30.0, 40.0);
    ego["behaviour"] = json!({"reaction_s": 0.5});
    let mut kid = sidewalk("kid", 10.0);
    kid["behaviour"] = json!({"yield": "never"});
    kid["start_when"] = json!({"agent": "ego", "condition": "within", "value": 16});
    let mut injured = lane("injured", "adult", "east", "in", 50.0, 0.0);
    injured["posture"] = json!("lying");
    let mut speeder = lane("speeder", "sedan", "east", "in", 20.0, 50.0);
    speeder["behaviour"] = json!({"speeding_pct": 20});
    let schema = straight(vec![ego, kid, injured, speeder]);
    let goals = "ego: goal { speed 40 km/h } goal { speed 20 km/h; start when kid starts }\n\
                 kid: goal { speed 3 m/s; lateral cross }\n\
                 speeder: goal { lateral hold_lane }\n";
    for plan in [Plan::Joint, Plan::Hierarchical] {
        let replies: Vec<&str> = match plan {
            Plan::Joint => vec![goals],
            Plan::Hierarchical => vec![
                "goal { speed 40 km/h } goal { speed 20 km/h; start when kid starts }",
                "goal { speed 3 m/s; lateral cross }",
                "goal { }",
                "goal { lateral hold_lane }",
            ],
        };
        let text = accepted(&schema, &replies, plan);
        for says in [
            "goal { speed 40 km/h }\n        goal { speed 20 km/h; start when kid starts }",
            "goal { speed 3 m/s; lateral cross; start when ego within 16 m }",
            "behaviour { yield never }",
            "behaviour { reaction 0.5 s }",
            "behaviour { speeding 20 % }",
            "posture lying",
        ] {
            assert!(text.contains(says), "{plan:?}: no `{says}` in\n{text}");
        }
    }
}

#[test]
fn every_trigger_condition_from_the_schema_checks() {
    for (condition, value, on, says) in [
        ("within", 20.0, "ego", "start when ego within 20 m"),
        ("ttc_under", 3.0, "ego", "start when ego ttc under 3 s"),
        ("headway_under", 1.5, "ego", "start when ego headway under 1.5 s"),
        ("reaches_kerb", 0.0, "first", "start when first reaches kerb"),
        ("starts", 0.0, "first", "start when first starts"),
    ] {
        let mut second = sidewalk("second", 20.0);
        second["start_when"] = json!({"agent": on, "condition": condition, "value": value});
        let schema = straight(vec![lane("ego", "sedan", "west", "in", 40.0, 30.0), sidewalk("first", 5.0), second]);
        let goals = "ego: goal { speed 30 km/h }\nfirst: goal { speed 1.4 m/s; lateral cross; start after 1 s }\n\
                     second: goal { speed 1.4 m/s; lateral cross }\n";
        let text = accepted(&schema, &[goals], Plan::Joint);
        assert!(text.contains(&format!("goal {{ speed 1.4 m/s; lateral cross; {says} }}")), "{condition}:\n{text}");
    }
}

#[test]
fn stop_line_ignore_and_a_reach_trigger_at_a_junction_check() {
    let at_line = |name: &str, arm: &str, dist: f64| {
        json!({"name": name, "kind": "sedan", "on": "lane", "arm": arm, "direction": "in", "lane": 1,
            "distance_m": dist, "relation": "before", "landmark": "stop_line", "speed_kmh": 30, "ego": name == "ego"})
    };
    let mut runner = at_line("runner", "west", 30.0);
    runner["behaviour"] = json!({"stop_line": "ignore", "yield": "never"});
    let mut ego = at_line("ego", "south", 20.0);
    ego["start_when"] = json!({"agent": "runner", "condition": "reaches_stop_line"});
    let schema = json!({"name": "runner", "brief": "a driver runs the stop line", "duration_s": 8,
        "road": {"template": "four_way", "lanes": 1, "speed_limit_kmh": 50},
        "agents": [ego, runner]});
    let goals = "ego: goal { speed 30 km/h; turn straight }\nrunner: goal { speed 30 km/h; turn straight }\n";
    let text = accepted(&schema, &[goals], Plan::Joint);
    assert!(text.contains("behaviour { yield never; stop_line ignore }"), "{text}");
    assert!(text.contains("goal { speed 30 km/h; turn straight; start when runner reaches stop_line }"), "{text}");
}

#[test]
fn a_goal_stage_start_wins_over_the_schema_trigger() {
    let mut kid = sidewalk("kid", 10.0);
    kid["start_when"] = json!({"agent": "ego", "condition": "within", "value": 16});
    let schema = straight(vec![lane("ego", "sedan", "west", "in", 30.0, 40.0), kid]);
    let text = accepted(
        &schema,
        &["ego: goal { speed 40 km/h }\nkid: goal { lateral cross; start after 2 s }\n"],
        Plan::Joint,
    );
    assert!(text.contains("goal { lateral cross; start after 2 s }") && !text.contains("within"), "{text}");
    // A trigger on an agent without a goal starts one.
    let text = accepted(&schema, &["ego: goal { speed 40 km/h }\n"], Plan::Joint);
    assert!(text.contains("goal { start when ego within 16 m }"), "{text}");
}

#[test]
fn unknown_words_in_the_schema_are_sent_back_for_correction() {
    let mut bad = straight(vec![lane("ego", "sedan", "west", "in", 30.0, 40.0), sidewalk("kid", 10.0)]);
    bad["agents"][1]["posture"] = json!("sitting");
    let mut good = bad.clone();
    good["agents"][1]["posture"] = json!("kneeling");
    let fake = serve(vec![chat(&bad.to_string()), chat(&good.to_string()), chat("ego: goal { speed 40 km/h }\n")]);
    let mut o = opts(&fake.url, Plan::Joint);
    o.max_repairs = 1;
    let (out, _) = llm::text_to_scenario("a kneeling child", &o, "scene.scn", &std::env::temp_dir());
    let Outcome::Accepted { text } = out else { panic!("{out:?}") };
    assert!(text.contains("posture kneeling"), "{text}");
    let reqs = fake.requests();
    let told = reqs[1]["messages"][3]["content"].as_str().expect("correction");
    assert!(told.contains("posture `sitting` is not one of standing, kneeling, lying"), "{told}");
    // The JSON schema sent for decoding names the words.
    let props = &reqs[0]["structured_outputs"]["json"]["properties"]["agents"]["items"]["properties"];
    assert_eq!(props["posture"]["enum"], json!(["standing", "kneeling", "lying"]));
    assert_eq!(props["behaviour"]["properties"]["yield"]["enum"], json!(["always", "never"]));
    assert!(props["start_when"]["properties"]["condition"]["enum"].as_array().is_some_and(|c| c.len() == 6));
}

#[test]
fn a_siren_from_the_schema_is_written_and_checked() {
    // A truck 20 m behind a car, on a straight road.
    let scene = |siren: Value, kind: &str| {
        let mut truck = lane("truck", kind, "west", "in", 50.0, 50.0);
        truck["siren"] = siren;
        straight(vec![truck, lane("ego", "sedan", "west", "in", 30.0, 30.0)])
    };
    let goals = "truck: goal { speed 50 km/h }\nego: goal { speed 30 km/h }\n";
    for (siren, says) in [(json!(false), "siren off"), (json!(true), "siren on")] {
        let text = accepted(&scene(siren, "fire_truck"), &[goals], Plan::Joint);
        assert!(text.contains(&format!("        {says}\n")), "{text}");
    }
    // On a kind that has none it is the checker's E0170, for the repair loop.
    let fake = serve(vec![chat(&scene(json!(false), "van").to_string()), chat(goals)]);
    let (out, _) = llm::text_to_scenario("a van", &opts(&fake.url, Plan::Joint), "scene.scn", &std::env::temp_dir());
    let Outcome::Rejected { diags, .. } = out else { panic!("{out:?}") };
    assert_eq!(diags[0].code, "E0170", "{}", diags[0].message);
}

#[test]
fn lamps_and_a_door_from_the_schema_are_written_and_checked() {
    // A van standing in the lane with its hazards on opens its door as the ego comes near.
    let scene = |kind: &str, beacons: Option<bool>| {
        let mut van = lane("van", kind, "west", "in", 10.0, 0.0);
        van["hazards"] = json!(true);
        van["door"] = json!({"door": "front_left", "open_when": {"agent": "ego", "condition": "within", "value": 15}});
        if let Some(b) = beacons {
            van["beacons"] = json!(b);
        }
        let mut ego = lane("ego", "sedan", "west", "in", 50.0, 30.0);
        ego["lights"] = json!(true);
        straight(vec![van, ego])
    };
    let goals = "van: goal { speed 0 km/h }\nego: goal { speed 30 km/h; stop behind van }\n";
    let text = accepted(&scene("van", None), &[goals], Plan::Joint);
    for says in ["hazards on", "door front_left open when ego within 15 m", "lights on"] {
        assert!(text.contains(&format!("        {says}\n")), "{says}: {text}");
    }
    let text = accepted(&scene("ambulance", Some(false)), &[goals], Plan::Joint);
    assert!(text.contains("        beacons off\n"), "{text}");
    // Beacons on a kind that has none: the checker's E0241, for the repair loop.
    let fake = serve(vec![chat(&scene("van", Some(true)).to_string()), chat(goals)]);
    let (out, _) = llm::text_to_scenario("a van", &opts(&fake.url, Plan::Joint), "scene.scn", &std::env::temp_dir());
    let Outcome::Rejected { diags, .. } = out else { panic!("{out:?}") };
    assert_eq!(diags[0].code, "E0241", "{}", diags[0].message);
    // The JSON schema sent for decoding offers the lamps and the doors by name.
    let reqs = fake.requests();
    let props = &reqs[0]["structured_outputs"]["json"]["properties"]["agents"]["items"]["properties"];
    for lamp in ["lights", "hazards", "beacons"] {
        assert_eq!(props[lamp]["type"], "boolean", "{lamp}");
    }
    let doors = &props["door"]["properties"];
    assert_eq!(doors["door"]["enum"], json!(["front_left", "front_right", "rear_left", "rear_right"]));
    assert_eq!(doors["open_when"]["properties"]["condition"]["enum"], json!(["within", "ttc_under"]));
}

#[test]
fn goal_grammars_admit_triggers_and_one_phase() {
    let single = gbnf::Grammar::parse(&llm::goals::single_grammar());
    for block in [
        "goal { speed 3 m/s; lateral cross; start when ego within 16 m }",
        "goal { start when ego ttc under 3 s }",
        "goal { start when ego headway under 1.5 s }",
        "goal { start when lead reaches stop_line }",
        "goal { start when kid reaches kerb }",
        "goal { start when lead starts }",
        "goal { speed 10 m/s } goal { speed 0 m/s; start when ego headway under 1.5 s }",
    ] {
        assert!(single.accepts(block), "{block}");
    }
    assert!(!single.accepts("goal { } goal { } goal { }"), "at most one phase when decoding");
    let joint = gbnf::Grammar::parse(&llm::goals::joint_grammar(&["lead".into(), "ego".into()]));
    assert!(joint.accepts(
        "lead: goal { speed 10 m/s } goal { speed 0 m/s; start when ego headway under 1.5 s }\nego: goal { speed 12 m/s }\n"
    ));
    // A phase on the line of its agent belongs to it; on a line of its own it has no name.
    let names = vec!["lead".to_string(), "ego".to_string()];
    let got = llm::goals::parse_joint(
        "lead: goal { speed 10 m/s } goal { speed 0 m/s; start when ego starts }\nego: goal { }",
        &names,
    )
    .expect("joint reply");
    assert_eq!(got[0], (0, "goal { speed 10 m/s }\ngoal { speed 0 m/s; start when ego starts }".to_string()));
    assert!(llm::goals::parse_joint("lead: goal { }\ngoal { speed 0 m/s }", &names).is_err());
    assert_eq!(
        llm::goals::parse_single("goal { speed 1 m/s }\ngoal { speed 0 m/s; start after 2 s }").expect("phases"),
        "goal { speed 1 m/s }\ngoal { speed 0 m/s; start after 2 s }"
    );
}

#[test]
fn phase_grammar_admits_stops_pulling_over_and_lane_changes_but_no_turn() {
    let single = gbnf::Grammar::parse(&llm::goals::single_grammar());
    for block in [
        "goal { speed 40 km/h } goal { stop after 30 m; start after 2 s }",
        "goal { speed 40 km/h } goal { lateral pull_to_shoulder; start when amb within 40 m }",
        "goal { speed 40 km/h } goal { speed 20 km/h; lateral pull_to_shoulder; stop after 30 m; start after 2 s }",
        "goal { speed 40 km/h } goal { lateral change_lane left; start when ego within 20 m }",
    ] {
        assert!(single.accepts(block), "{block}");
    }
    for block in [
        "goal { speed 40 km/h } goal { turn left; start after 2 s }",
        "goal { speed 40 km/h } goal { lateral cross; start after 2 s }",
        "goal { speed 40 km/h } goal { lateral pull_to_shoulder; lateral change_lane left; start after 2 s }",
        "goal { speed 40 km/h } goal { stop at stop_line; start after 2 s }",
        "goal { speed 40 km/h } goal { speed 0 m/s }",
    ] {
        assert!(!single.accepts(block), "a phase that the checker refuses (or without a start): {block}");
    }
    let joint = gbnf::Grammar::parse(&llm::goals::joint_grammar(&["car".into(), "ego".into()]));
    assert!(joint.accepts(
        "car: goal { speed 40 km/h } goal { lateral pull_to_shoulder; stop after 25 m; start when ego within 30 m }\nego: goal { }\n"
    ));
}

#[test]
fn a_phase_that_pulls_over_and_stops_from_the_model_checks() {
    let schema =
        straight(vec![lane("ego", "sedan", "west", "in", 60.0, 40.0), lane("car", "sedan", "west", "in", 30.0, 40.0)]);
    let goals = "ego: goal { speed 40 km/h }\n\
                 car: goal { speed 40 km/h } goal { speed 20 km/h; lateral pull_to_shoulder; stop after 25 m; start when ego within 25 m }\n";
    for plan in [Plan::Joint, Plan::Hierarchical] {
        let replies: Vec<&str> = match plan {
            Plan::Joint => vec![goals],
            _ => goals.lines().map(|l| l.split_once(": ").expect("name").1).collect(),
        };
        let text = accepted(&schema, &replies, plan);
        // The writer may break a long block over lines; its words and their order are what count.
        let words = text.replace(';', " ").split_whitespace().collect::<Vec<_>>().join(" ");
        let phase = "goal { speed 40 km/h } goal { speed 20 km/h lateral pull_to_shoulder stop after 25 m start when ego within 25 m }";
        assert!(words.contains(phase), "{plan:?}:\n{text}");
    }
}

#[test]
fn a_phase_that_changes_lane_from_the_model_checks() {
    let mut schema =
        straight(vec![lane("ego", "sedan", "west", "in", 60.0, 50.0), lane("car", "sedan", "west", "in", 30.0, 40.0)]);
    schema["road"]["lanes"] = json!(2);
    schema["agents"][1]["lane"] = json!(2);
    let goals = "ego: goal { speed 50 km/h }\ncar: goal { speed 40 km/h } goal { lateral change_lane left; start when ego within 20 m }\n";
    let text = accepted(&schema, &[goals], Plan::Joint);
    let words = text.replace(';', " ").split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        words.contains("goal { speed 40 km/h } goal { lateral change_lane left start when ego within 20 m }"),
        "{text}"
    );
}

#[test]
fn the_grammar_export_has_the_rare_vocabulary() {
    for (format, def) in [(rocc::grammar::Format::Gbnf, " ::= "), (rocc::grammar::Format::Lark, ": ")] {
        let g = rocc::grammar::print(&rocc::grammar::language(), format);
        for rule in [
            "posture_stmt",
            "behaviour",
            "behaviour_set",
            "trigger",
            "kw_when",
            "kw_under",
            "siren_stmt",
            "lamp_stmt",
            "door_stmt",
        ] {
            let rule = if def == ": " { rule.to_string() } else { rule.replace('_', "-") };
            assert!(g.lines().any(|l| l.starts_with(&format!("{rule}{def}"))), "{format:?} has no rule `{rule}`");
        }
    }
    let g = gbnf::Grammar::parse(&rocc::grammar::print(&rocc::grammar::language(), rocc::grammar::Format::Gbnf));
    let scene = "scenario s {\n    duration 4 s\n    road straight { lanes 1 }\n    agent kid: child {\n        at west.in[1], 5 m before center\n        posture kneeling\n        goal { speed 1 m/s; lateral cross; start when ego within 10 m }\n        goal { speed 2 m/s; start when ego ttc under 2 s }\n        behaviour { yield never; reaction 1 s }\n    }\n    agent amb: ambulance { at east.in[1], 40 m before center; speed 30 km/h; siren off; beacons on }\n    object parked: sedan { at east.out[1], 10 m after center; hazards off; door front_left open when kid within 8 m; door front_left close at 3 s }\n}\n";
    assert!(g.accepts(scene), "the GBNF rejects the rare vocabulary");
}

#[test]
fn parking_driveways_and_a_reverse_goal_from_the_model_check() {
    let mut car = json!({"name": "car", "kind": "sedan", "on": "driveway", "driveway": "home", "arm": "east",
        "direction": "out", "lane": 1, "distance_m": 0, "relation": "after", "landmark": "center", "speed_kmh": 0,
        "ego": false});
    car["start_when"] = json!({"agent": "van", "condition": "within", "value": 60});
    let parked = json!({"name": "parked", "kind": "sedan", "on": "parking", "slot": 3, "arm": "east",
        "direction": "out", "lane": 1, "distance_m": 0, "relation": "after", "landmark": "center", "speed_kmh": 0,
        "ego": false});
    let van = lane("van", "van", "west", "in", 50.0, 30.0);
    let schema = json!({"name": "backing_out", "brief": "a car backs out of a driveway into traffic", "duration_s": 10,
        "road": {"template": "straight", "lanes": 1, "sidewalks": true, "parking": [{"arm": "east", "side": "out"}],
            "driveways": [{"name": "home", "arm": "east", "direction": "out", "distance_m": 30}]},
        "agents": [car, parked, van]});
    let goals = "car: goal { speed 2 m/s; reverse into east.out[1] }\nvan: goal { speed 30 km/h }\n";
    let text = accepted(&schema, &[goals], Plan::Joint);
    for says in [
        "parking east out",
        "driveway home east.out 30 m",
        "at driveway(home)",
        "at parking(east.out)[3]",
        "goal { speed 2 m/s; reverse into east.out[1]; start when van within 60 m }",
    ] {
        assert!(text.contains(says), "no `{says}` in\n{text}");
    }
    // The goal grammars and the language export admit the reverse goal and kerbside places.
    let single = gbnf::Grammar::parse(&llm::goals::single_grammar());
    for block in ["goal { reverse 8 m }", "goal { speed 2 m/s; reverse into east.out[1]; start after 1 s }"] {
        assert!(single.accepts(block), "{block}");
    }
    let g = gbnf::Grammar::parse(&rocc::grammar::print(&rocc::grammar::language(), rocc::grammar::Format::Gbnf));
    assert!(g.accepts(&text), "the GBNF rejects\n{text}");
    // A side word the schema does not know is sent back.
    let mut bad = schema.clone();
    bad["road"]["parking"][0]["side"] = json!("left");
    let fake = serve(vec![chat(&bad.to_string())]);
    let (out, _) = llm::text_to_scenario("parking", &opts(&fake.url, Plan::Joint), "scene.scn", &std::env::temp_dir());
    assert!(!matches!(out, Outcome::Accepted { .. }), "{out:?}");
    let reqs = fake.requests();
    let road = &reqs[0]["structured_outputs"]["json"]["properties"]["road"]["properties"];
    assert_eq!(road["parking"]["items"]["properties"]["side"]["enum"], json!(["in", "out", "both"]));
}

#[test]
fn signals_and_a_red_light_runner_from_the_schema_check() {
    let at_line = |name: &str, arm: &str, dist: f64| {
        json!({"name": name, "kind": "sedan", "on": "lane", "arm": arm, "direction": "in", "lane": 1,
            "distance_m": dist, "relation": "before", "landmark": "stop_line", "speed_kmh": 43, "ego": name == "ego"})
    };
    let mut runner = at_line("runner", "south", 30.0);
    runner["behaviour"] = json!({"signal": "ignore"});
    let schema = json!({"name": "runner", "brief": "a driver runs the red", "duration_s": 8,
        "road": {"template": "four_way", "lanes": 1, "speed_limit_kmh": 50, "signals": true,
            "signal_green_s": 6, "signal_offset_s": 9},
        "agents": [at_line("ego", "west", 60.0), runner]});
    let goals = "ego: goal { speed 43 km/h; turn straight }\nrunner: goal { speed 43 km/h; turn straight }\n";
    let text = accepted(&schema, &[goals], Plan::Joint);
    assert!(
        text.contains(
            "road four_way { lanes 1; speed_limit 50 km/h; signals on; signal_green 6 s; signal_offset 9 s }"
        ),
        "{text}"
    );
    assert!(text.contains("behaviour { signal ignore }"), "{text}");
}

#[test]
fn flaggers_from_the_schema_stand_beside_their_lane_facing_its_traffic() {
    let mut west = lane("west_flagger", "adult", "west", "in", 30.0, 0.0);
    west["flag"] = json!({"shows": "stop", "switch_after_s": 8});
    let mut east = lane("east_flagger", "adult", "east", "in", 30.0, 0.0);
    east["flag"] = json!({"shows": "go", "switch_when": {"agent": "car", "condition": "within", "value": 15}});
    // Listed first, a flagger is still no ego: the first mover is.
    let schema = json!({"name": "work_zone", "brief": "flaggers at a work zone", "duration_s": 10,
        "road": {"template": "straight", "lanes": 1, "speed_limit_kmh": 50},
        "agents": [west, east, lane("car", "sedan", "west", "in", 55.0, 30.0)]});
    for (plan, replies) in [
        (Plan::Joint, vec!["car: goal { speed 30 km/h }\nwest_flagger: goal { speed 5 km/h }\n"]),
        (Plan::Hierarchical, vec!["goal { speed 30 km/h }"]),
    ] {
        let text = accepted(&schema, &replies, plan);
        for says in [
            "egos [car]",
            "agent west_flagger: adult {\n        at west.in[1], 30 m before center offset 2.5 m right heading 180 deg\n        flag { stop; go after 8 s }\n    }",
            "agent east_flagger: adult {\n        at east.in[1], 30 m before center offset 2.5 m right heading 0 deg\n        flag { go; stop when car within 15 m }\n    }",
        ] {
            assert!(text.contains(says), "{plan:?}: no `{says}` in\n{text}");
        }
        assert!(!text.contains("speed 5 km/h"), "a flagger's goal from the goal stage is dropped:\n{text}");
    }
}

#[test]
fn a_near_miss_from_the_schema_is_written_and_staged() {
    let mut s = json!({"name": "overtake", "brief": "a close pass", "duration_s": 6,
        "road": {"template": "straight", "lanes": 2, "speed_limit_kmh": 80},
        "agents": [lane("v1", "sedan", "west", "in", 50.0, 72.0), lane("v2", "van", "west", "in", 25.0, 43.2)],
        "near_misses": [{"passer": "v1", "passed": "v2", "gap_m": 0.4, "at_s": 3}]});
    s["agents"][0]["lane"] = json!(2);
    let goals = "v1: goal { speed 72 km/h }\nv2: goal { speed 43.2 km/h }\n";
    let text = accepted(&s, &[goals], Plan::Joint);
    assert!(text.contains("\n    near_miss { passer v1; passed v2; gap 0.4 m; at 3 s }\n"), "{text}");
    // A side that is no side goes back to the model.
    let mut bad = s.clone();
    bad["near_misses"][0]["side"] = json!("above");
    assert_eq!(
        rocc::llm::schema::parse(&bad.to_string()).expect_err("refused"),
        "near miss side `above` is not one of left, right"
    );
}

/// A close call by time to collision: the rear approach of
/// tests/near-miss/rear-approach-at-under-a-second.scn, stated as the model would.
#[test]
fn a_ttc_near_miss_from_the_schema_is_written_and_staged() {
    let s = json!({"name": "tailgate", "brief": "a sedan closes on a van to under a second", "duration_s": 6,
        "road": {"template": "straight", "lanes": 1, "speed_limit_kmh": 60},
        "agents": [lane("v1", "sedan", "west", "in", 60.0, 54.0), lane("v2", "van", "west", "in", 35.0, 36.0)],
        "near_misses": [{"passer": "v1", "passed": "v2", "ttc_s": 0.8, "at_s": 3}]});
    let goals = "v1: goal { speed 54 km/h }\nv2: goal { speed 36 km/h }\n";
    let text = accepted(&s, &[goals], Plan::Joint);
    assert!(text.contains("\n    near_miss { passer v1; passed v2; ttc 0.8 s; at 3 s }\n"), "{text}");
    // Both forms, neither, or a side on the `ttc` form go back to the model.
    for (field, value, says) in [
        ("gap_m", json!(0.4), "a near miss takes one of gap_m (a pass alongside) and ttc_s (a time to collision)"),
        ("ttc_s", json!(null), "a near miss takes one of gap_m (a pass alongside) and ttc_s (a time to collision)"),
        ("side", json!("left"), "a near miss by ttc_s takes no side"),
        ("ttc_s", json!(-1), "a near miss's gap_m and ttc_s must be positive and at_s non-negative"),
    ] {
        let mut bad = s.clone();
        bad["near_misses"][0][field] = value;
        assert_eq!(rocc::llm::schema::parse(&bad.to_string()).expect_err("refused"), says, "{field}");
    }
    let v = rocc::llm::schema::json_schema(&["sedan".to_string()]);
    let item = &v["properties"]["near_misses"]["items"];
    assert_eq!(item["required"], json!(["passer", "passed"]));
    assert_eq!(item["properties"]["ttc_s"]["minimum"], json!(0.5));
}

#[test]
fn the_schema_and_the_grammar_export_name_signals_flaggers_and_near_misses() {
    let v = rocc::llm::schema::json_schema(&["sedan".to_string(), "adult".to_string()]);
    let agent = &v["properties"]["agents"]["items"]["properties"];
    assert_eq!(agent["flag"]["properties"]["shows"]["enum"], json!(["stop", "go"]));
    assert_eq!(agent["flag"]["properties"]["switch_when"], agent["start_when"]);
    assert_eq!(agent["behaviour"]["properties"]["signal"]["enum"], json!(["obey", "ignore"]));
    assert_eq!(v["properties"]["road"]["properties"]["signals"]["type"], "boolean");
    assert_eq!(v["properties"]["near_misses"]["items"]["properties"]["side"]["enum"], json!(["left", "right"]));
    for (format, def) in [(rocc::grammar::Format::Gbnf, " ::= "), (rocc::grammar::Format::Lark, ": ")] {
        let g = rocc::grammar::print(&rocc::grammar::language(), format);
        for rule in ["flag", "flag_step", "kw_flag", "near_miss", "near_miss_field"] {
            let rule = if def == ": " { rule.to_string() } else { rule.replace('_', "-") };
            assert!(g.lines().any(|l| l.starts_with(&format!("{rule}{def}"))), "{format:?} has no rule `{rule}`");
        }
    }
    let g = gbnf::Grammar::parse(&rocc::grammar::print(&rocc::grammar::language(), rocc::grammar::Format::Gbnf));
    let scene = "scenario s {\n    duration 4 s\n    road four_way { lanes 1; signals on; signal_north 0..12 s }\n    agent f: adult {\n        at west.in[1], 5 m before center offset 2.5 m right heading 180 deg\n        flag { stop; go after 3 s; stop when car within 10 m }\n    }\n    agent car: sedan { at west.in[1], 40 m before center; behaviour { signal ignore } }\n    near_miss { passer car; passed f; gap 0.5 m; side right; at 2 s }\n}\n";
    assert!(g.accepts(scene), "the GBNF rejects signals, flags or near misses");
}
