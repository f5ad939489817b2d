//! Triggers and behaviour, tested on the tracks of the scenes in `tests/behaviour-cases/`
//! (each says in its first line what it shows) and of their careful twins.

#[path = "support/contact.rs"]
mod contact;
#[path = "support/front.rs"]
mod front;

use contact::obb;
use front::front_of;
use rocc::rollout::Tracks;

fn case(name: &str) -> String {
    std::fs::read_to_string(format!("tests/behaviour-cases/{name}.scn")).expect("case")
}

/// The scene with its `behaviour` block removed: the careful twin.
fn careful(text: &str) -> String {
    text.lines().filter(|l| !l.trim_start().starts_with("behaviour")).collect::<Vec<_>>().join("\n")
}

fn idx(t: &Tracks, name: &str) -> usize {
    t.agents.iter().position(|a| a.name == name).expect("agent")
}

/// The first frame agent `i` moves off its first pose.
fn first_move(t: &Tracks, i: usize) -> usize {
    let p0 = t.poses[i][0];
    (0..t.frames).find(|&f| (t.poses[i][f].x - p0.x).hypot(t.poses[i][f].y - p0.y) > 1e-6).expect("moves")
}

fn dist(t: &Tracks, a: usize, b: usize, f: usize) -> f64 {
    let (p, q) = (t.poses[a][f], t.poses[b][f]);
    (p.x - q.x).hypot(p.y - q.y)
}

/// Frames where the kid's box reaches into the car's lane (3.5 m wide, centred on the car's
/// line) ahead of the car, with the car under 20 m away.
fn kid_in_lane_near_car(t: &Tracks) -> usize {
    let (kid, car) = (idx(t, "kid"), idx(t, "car"));
    let half_kid = t.agents[kid].size[1] / 2.0;
    (0..t.frames)
        .filter(|&f| {
            let (k, c) = (t.poses[kid][f], t.poses[car][f]);
            (k.y - c.y).abs() < 1.75 + half_kid && k.x > c.x && dist(t, kid, car, f) < 20.0
        })
        .count()
}

#[test]
fn a_child_that_does_not_yield_darts_out_in_front_of_the_car() {
    let f = front_of(&case("child-darts-out"));
    let t = &f.tracks;
    assert!(
        kid_in_lane_near_car(t) >= 10,
        "the child is in the car's lane near it for {} frames",
        kid_in_lane_near_car(t)
    );
    // The car brakes for it (and stops short of it).
    let car = idx(t, "car");
    let slowest = t.speeds[car].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(slowest < 1.0, "the car did not brake for the child: {slowest:.2} m/s");
    for fr in 0..t.frames {
        let (a, b) = (obb(t, car, fr), obb(t, idx(t, "kid"), fr));
        assert!(!a.overlaps(&b), "the car ran into the child at frame {fr}");
    }
    // Its careful twin waits at the kerb till the car has passed.
    let f = front_of(&careful(&case("child-darts-out")));
    assert_eq!(kid_in_lane_near_car(&f.tracks), 0, "the careful child stepped in front of the car");
}

/// The northbound car's front, furthest north it gets while the bus is short of clearing its lane.
fn furthest_before_the_bus_clears(t: &Tracks) -> (f64, f64) {
    let (bus, late) = (idx(t, "first"), idx(t, "late"));
    let clear = (0..t.frames).find(|&f| t.poses[bus][f].x - t.agents[bus].size[0] / 2.0 > 4.0).unwrap_or(t.frames);
    let front = (0..clear).map(|f| t.poses[late][f].y + t.agents[late].size[0] / 2.0).fold(f64::MIN, f64::max);
    let slowest = (0..clear).map(|f| t.speeds[late][f]).fold(f64::INFINITY, f64::min);
    (front, slowest)
}

#[test]
fn a_driver_that_ignores_its_stop_line_rolls_past_it_and_one_that_never_yields_goes_through() {
    let text = case("stop-line-ignored");
    let (careful_front, careful_slowest) = furthest_before_the_bus_clears(&front_of(&careful(&text)).tracks);
    assert!(careful_slowest < 0.05, "the careful driver did not hold: {careful_slowest:.2} m/s");
    let (front, _) = furthest_before_the_bus_clears(&front_of(&text).tracks);
    assert!(
        front > careful_front + 3.0,
        "ignoring its line, the car's front got to y = {front:.1}, the careful one's to {careful_front:.1}"
    );
    // `yield never`: it does not stop at all, and crosses the bus's path first.
    let t = &front_of(&text.replace("stop_line ignore", "yield never")).tracks;
    let late = idx(t, "late");
    let slowest = t.speeds[late].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(slowest > 3.0, "the driver that never yields slowed to {slowest:.2} m/s");
    let crossed = (0..t.frames).find(|&f| t.poses[late][f].y - t.agents[late].size[0] / 2.0 > 0.0).expect("crosses");
    let bus = idx(t, "first");
    assert!(t.poses[bus][crossed].x + t.agents[bus].size[0] / 2.0 < 0.0, "the bus went first");
}

#[test]
fn a_reach_trigger_starts_an_agent_when_the_other_is_at_its_stop_line() {
    let text = careful(&case("stop-line-ignored")).replace(
        "    agent late: sedan {",
        "    agent third: sedan {\n        at east.in[1], 30 m before stop_line\n        \
         goal { speed 6 m/s; turn straight; start when late reaches stop_line }\n    }\n    agent late: sedan {",
    );
    let f = front_of(&text);
    let t = &f.tracks;
    let (late, third) = (idx(t, "late"), idx(t, "third"));
    // The south approach's stop line: across `late`'s lane, south of the centre.
    let x = t.poses[late][0].x;
    let line = f
        .map
        .stop_lines
        .iter()
        .find(|l| (l.a.y - l.b.y).abs() < 1e-6 && l.a.y < 0.0 && l.a.x.min(l.b.x) <= x && x <= l.a.x.max(l.b.x))
        .expect("a stop line")
        .a
        .y;
    // The trigger holds from 0.5 m short of the line.
    let front = |f: usize| t.poses[late][f].y + t.agents[late].size[0] / 2.0;
    let reached = (0..t.frames).find(|&f| front(f) >= line - 0.5 - 1e-6).expect("reaches its line");
    assert_eq!(first_move(t, third), reached + 1, "`late` reached its line at frame {reached}");
}

#[test]
fn a_speeding_driver_drives_over_the_limit() {
    let top = |text: &str| {
        let t = &front_of(text).tracks;
        t.speeds[idx(t, "car")].iter().cloned().fold(0.0, f64::max)
    };
    let text = case("speeding");
    let (fast, calm) = (top(&text), top(&careful(&text)));
    assert!((fast - 60.0 / 3.6).abs() < 0.2, "the speeding car reached {:.1} km/h", fast * 3.6);
    assert!((calm - 40.0 / 3.6).abs() < 1e-9, "the careful car reached {:.1} km/h", calm * 3.6);
}

/// The first frame agent `i` decelerates by more than 0.5 m/s2.
fn braking_begins(t: &Tracks, i: usize) -> usize {
    let dt = 1.0 / t.rate;
    (1..t.frames).find(|&f| (t.speeds[i][f - 1] - t.speeds[i][f]) / dt > 0.5).expect("brakes")
}

#[test]
fn a_reaction_time_delays_when_braking_begins() {
    let text = case("late-reaction");
    let late = front_of(&text);
    let calm = front_of(&careful(&text));
    let (t, c) = (&late.tracks, &calm.tracks);
    let car = idx(t, "car");
    let delay = (braking_begins(t, car) as f64 - braking_begins(c, car) as f64) / t.rate;
    assert!((1.4..=1.7).contains(&delay), "braking began {delay:.2} s later");
    // It stops short of the stalled car all the same, braking harder.
    let hardest =
        |t: &Tracks| (1..t.frames).map(|f| (t.speeds[car][f - 1] - t.speeds[car][f]) * t.rate).fold(0.0, f64::max);
    assert!(hardest(t) > hardest(c) + 0.5, "{:.2} vs {:.2} m/s2", hardest(t), hardest(c));
    let stalled = idx(t, "stalled");
    assert!((0..t.frames).all(|f| !obb(t, car, f).overlaps(&obb(t, stalled, f))));
}

#[test]
fn a_trigger_starts_a_walker_when_the_car_comes_within_its_distance() {
    let t = &front_of(&case("walker-starts-on-approach")).tracks;
    let (walker, car) = (idx(t, "walker"), idx(t, "car"));
    let within = (0..t.frames).find(|&f| dist(t, walker, car, f) <= 30.0).expect("comes within 30 m");
    assert!(dist(t, walker, car, within - 1) > 30.0);
    // Read on frame `within`, it starts the goal for the step to the next frame.
    assert_eq!(
        first_move(t, walker),
        within + 1,
        "started at frame {}, the car came within at {within}",
        first_move(t, walker)
    );
}

#[test]
fn time_to_collision_headway_and_start_triggers_fire_when_their_condition_holds() {
    let base = case("walker-starts-on-approach");
    // Time to collision: the gap between bounding circles over the closing speed.
    let t = &front_of(&base.replace("start when car within 30 m", "start when car ttc under 3 s")).tracks;
    let (walker, car) = (idx(t, "walker"), idx(t, "car"));
    let radius = |i: usize| 0.5 * t.agents[i].size[0].hypot(t.agents[i].size[1]);
    let ttc = |f: usize| {
        let (w, c) = (t.poses[walker][f], t.poses[car][f]);
        let d = glam::DVec2::new(w.x - c.x, w.y - c.y);
        let closing = glam::DVec2::from_angle(c.yaw).dot(d) * t.speeds[car][f] / d.length();
        (d.length() - radius(walker) - radius(car)).max(0.0) / closing
    };
    let go = first_move(t, walker);
    assert!(ttc(go - 1) <= 3.0 && ttc(go - 2) > 3.0, "ttc {:.2} then {:.2}", ttc(go - 2), ttc(go - 1));
    // `starts`: a second walker sets off one step after the first does.
    let chained = base.replace(
        "    agent car: sedan {",
        "    agent second: adult {\n        at sidewalk(east.out), 19 m after center\n        \
         goal { speed 1.4 m/s; lateral cross; start when walker starts }\n    }\n    agent car: sedan {",
    );
    let t = &front_of(&chained).tracks;
    assert_eq!(first_move(t, idx(t, "second")), first_move(t, idx(t, "walker")) + 1);
    // Headway: the follower's time to reach the stalled car's rear at its speed.
    let text = careful(&case("late-reaction"))
        .replace("goal { speed 0 m/s }", "goal { speed 10 m/s; start when car headway under 2 s }");
    let t = &front_of(&text).tracks;
    let (lead, car) = (idx(t, "stalled"), idx(t, "car"));
    let headway = |f: usize| {
        let gap = t.poses[lead][f].x - t.poses[car][f].x - (t.agents[lead].size[0] + t.agents[car].size[0]) / 2.0;
        gap / t.speeds[car][f]
    };
    let go = first_move(t, lead);
    assert!(
        headway(go - 1) <= 2.0 && headway(go - 2) > 2.0,
        "headway {:.2} then {:.2}",
        headway(go - 2),
        headway(go - 1)
    );
}

#[test]
fn a_later_goal_block_takes_over_when_its_trigger_holds() {
    let t = &front_of(&case("lead-brakes-on-approach")).tracks;
    let (lead, car) = (idx(t, "lead"), idx(t, "car"));
    let headway = |f: usize| {
        let gap = t.poses[lead][f].x - t.poses[car][f].x - (t.agents[lead].size[0] + t.agents[car].size[0]) / 2.0;
        gap / t.speeds[car][f]
    };
    let under = (0..t.frames).find(|&f| headway(f) <= 1.5).expect("closes in");
    // Till then the lead holds its first goal's speed; from the step after, it brakes to a stop.
    assert!((0..=under).all(|f| (t.speeds[lead][f] - 10.0).abs() < 1e-9), "the lead slowed before its phase");
    assert!(t.speeds[lead][under + 2] < t.speeds[lead][under + 1] && t.speeds[lead][under + 1] < 10.0);
    assert!(t.speeds[lead][t.frames - 1] < 0.05, "the lead did not stop");
    assert!((0..t.frames).all(|f| !obb(t, lead, f).overlaps(&obb(t, car, f))));
}

#[test]
fn a_phase_that_waits_on_an_agent_waiting_for_its_owner_is_no_cycle() {
    // The lead's first goal starts at once; its phase waits on the car, which waits on that start.
    let text = case("lead-brakes-on-approach")
        .replace("goal { speed 15 m/s }", "goal { speed 15 m/s; start when lead starts }");
    let t = &front_of(&text).tracks;
    assert!(t.speeds[idx(t, "lead")][t.frames - 1] < 0.05, "the lead's phase did not start");
    // Two first goals waiting on each other are a cycle.
    let cyclic = text.replace("goal { speed 10 m/s }", "goal { speed 10 m/s; start when car starts }");
    let mut sources = rocc::source::SourceMap::default();
    let d = rocc::check::check_text("t.scn", &cyclic, std::path::Path::new("."), &mut sources).expect_err("a cycle");
    assert_eq!(d[0].code, "E0151", "{:?}", d[0].message);
    assert_eq!(d[0].labels.len(), 2);
}

#[test]
fn triggers_and_behaviour_format_to_text_that_checks_the_same() {
    for name in [
        "child-darts-out",
        "late-reaction",
        "stop-line-ignored",
        "walker-starts-on-approach",
        "lead-brakes-on-approach",
    ] {
        let text = case(name).replace("start when car within 30 m", "start when car ttc under 3 s");
        let once = rocc::syntax::format_source(&text).expect("formats");
        assert_eq!(once, rocc::syntax::format_source(&once).expect("formats again"), "{name}");
        let check = |t: &str| {
            let s = rocc::check::check_text("a.scn", t, std::path::Path::new("."), &mut Default::default());
            ron::to_string(&s.expect("checks")).expect("ron")
        };
        assert_eq!(check(&text), check(&once), "{name}: formatting changed the checked scenario");
        assert!(once.contains("behaviour {") || once.contains("start when"), "{once}");
    }
}

fn check_code(text: &str) -> &'static str {
    let mut sources = rocc::source::SourceMap::default();
    rocc::check::check_text("t.scn", text, std::path::Path::new("."), &mut sources).expect_err("refused")[0].code
}

#[test]
fn a_goal_phase_pulls_over_and_stops_on_its_own_trigger() {
    let text = case("car-pulls-over-and-stops-on-a-trigger");
    let t = &front_of(&text).tracks;
    let (lead, ego) = (idx(t, "lead"), idx(t, "ego"));
    let fired = (0..t.frames).find(|&f| dist(t, lead, ego, f) <= 25.0).expect("the ego closes in");
    // In its lane at its speed till its condition holds; the phase runs from the next step.
    assert!((0..=fired).all(|f| (t.poses[lead][f].y + 1.75).abs() < 1e-9 && (t.speeds[lead][f] - 8.0).abs() < 1e-9));
    // Then onto the shoulder (lane edge at y = -3.5, shoulder to -6), stopped 40 m on.
    let end = t.poses[lead][t.frames - 1];
    let half_w = t.agents[lead].size[1] / 2.0;
    assert!(end.y + half_w < -3.3 && end.y - half_w > -6.0, "the lead is at y = {:.2}", end.y);
    assert!(t.speeds[lead][t.frames - 1] < 0.05, "the lead did not stop");
    let run = end.x - t.poses[lead][fired].x;
    assert!((run - 40.0).abs() < 1.0, "stopped {run:.2} m on");
    // The ego drives past it in its lane.
    assert!(t.poses[ego][t.frames - 1].x > end.x + 10.0 && (t.poses[ego][t.frames - 1].y + 1.75).abs() < 0.05);
    assert!((0..t.frames).all(|f| !obb(t, lead, f).overlaps(&obb(t, ego, f))));
    // What a phase cannot change is E0155: its route, another lateral move, nothing at all.
    let phase = "goal { lateral pull_to_shoulder; stop after 40 m; start when ego within 25 m }";
    for (with, why) in [
        ("goal { turn left; start when ego within 25 m }", "a turn"),
        ("goal { start when ego within 25 m }", "nothing"),
    ] {
        assert_eq!(check_code(&text.replace(phase, with)), "E0155", "{why}");
    }
    let after_easing = text.replace("goal { speed 8 m/s }", "goal { speed 8 m/s; lateral away_from ego }");
    assert_eq!(check_code(&after_easing), "E0155");
}

#[test]
fn a_goal_phase_changes_lane_on_its_own_trigger() {
    let text = case("car-changes-lane-on-a-trigger");
    let t = &front_of(&text).tracks;
    let (car, ego) = (idx(t, "car"), idx(t, "ego"));
    let fired = (0..t.frames).find(|&f| dist(t, car, ego, f) <= 20.0).expect("the ego closes in");
    // In the outer lane (centre y = -5.25) till its condition holds, in the inner one (y = -1.75)
    // by the end, its box never outside the two (the road's right edge is at y = -7).
    assert!((0..=fired).all(|f| (t.poses[car][f].y + 5.25).abs() < 1e-6), "moved before the trigger");
    assert!((t.poses[car][t.frames - 1].y + 1.75).abs() < 0.05, "ends at y = {:.2}", t.poses[car][t.frames - 1].y);
    let half_w = t.agents[car].size[1] / 2.0;
    assert!((0..t.frames).all(|f| t.poses[car][f].y + half_w < 0.0 && t.poses[car][f].y - half_w > -7.0));
    assert!((0..t.frames).all(|f| !obb(t, car, f).overlaps(&obb(t, ego, f))));
    // Once per agent, from a first goal that holds its lane and does not turn.
    // (Indented, so that the scene's first comment, which quotes the phase, stays as it is.)
    let phase = "        goal { lateral change_lane left; start when ego within 20 m }";
    let twice = format!("{phase}\n        goal {{ lateral pull_to_shoulder; start after 9 s }}");
    assert_eq!(check_code(&text.replace(phase, &twice)), "E0156");
    let turned = text.replace("goal { speed 10 m/s }", "goal { speed 10 m/s; lateral change_lane left }");
    assert_eq!(check_code(&turned), "E0156");
    // To a lane that exists: lane 2 of two is the outermost.
    let right = "        goal { lateral change_lane right; start when ego within 20 m }";
    assert_eq!(check_code(&text.replace(phase, right)), "E0156");
}
