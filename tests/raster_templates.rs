//! BEV rasters of the real road templates and of every example: layer containment and symmetry
//! properties per template, and a snapshot per example clip of frame 0's per-channel pixel
//! counts with a coarse ASCII thumbnail (what changed is visible in a review diff).

use proptest::prelude::*;
use rocc::check::scenario::{Road, Template};
use rocc::compile::{frame_boxes, front};
use rocc::place::Pose;
use rocc::raster::layout::*;
use rocc::raster::{Bev, rasterize};
use rocc::source::SourceMap;
use std::fmt::Write;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn road(template: Template, lanes: u32, width: f64, crosswalks: bool, sidewalks: bool, shoulder: f64) -> Road {
    Road {
        template,
        lanes,
        lane_width: width,
        speed_limit: 50.0 / 3.6,
        shoulder,
        median: 0.0,
        crosswalks,
        sidewalks,
        length: if template.has_junction() { 60.0 } else { 120.0 },
        radius: if template == Template::Roundabout { 18.0 } else { 120.0 },
        angle: 40f64.to_radians(),
    }
}

fn plane(b: &Bev, ch: usize) -> ndarray::ArrayView2<'_, i8> {
    b.masks.index_axis(ndarray::Axis(0), ch)
}

/// Pixels set in `inner` with no pixel of any `outer` channel within one pixel: two fills of a
/// shared edge may round to neighbouring pixel rows, never further apart.
fn outside(b: &Bev, inner: usize, outer: &[usize]) -> usize {
    let p = plane(b, inner);
    let near = |i: usize, j: usize| {
        (i.saturating_sub(1)..=(i + 1).min(GRID - 1)).any(|r| {
            (j.saturating_sub(1)..=(j + 1).min(GRID - 1)).any(|c| outer.iter().any(|&o| b.masks[[o, r, c]] != 0))
        })
    };
    p.indexed_iter().filter(|&((i, j), &v)| v != 0 && !near(i, j)).count()
}

/// Set, and so are its four neighbours.
fn interior(b: &Bev, ch: usize, i: usize, j: usize) -> bool {
    let set = |i: usize, j: usize| i < GRID && j < GRID && b.masks[[ch, i, j]] != 0;
    i > 0 && j > 0 && set(i, j) && set(i - 1, j) && set(i + 1, j) && set(i, j - 1) && set(i, j + 1)
}

/// Pixels set in `a` with no set pixel of `b` within one pixel (a 1-px line whose position
/// rounds differently under rotation still matches).
fn unmatched(a: ndarray::ArrayView2<i8>, b: ndarray::ArrayView2<i8>) -> usize {
    a.indexed_iter()
        .filter(|&((i, j), &v)| {
            v != 0
                && !(i.saturating_sub(1)..=(i + 1).min(GRID - 1))
                    .any(|p| (j.saturating_sub(1)..=(j + 1).min(GRID - 1)).any(|q| b[[p, q]] != 0))
        })
        .count()
}

const TEMPLATES: [Template; 6] = [
    Template::Straight,
    Template::Curve,
    Template::FourWay,
    Template::TJunction,
    Template::Merge,
    Template::Roundabout,
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Lanes and crosswalks lie on drivable area; the boundary outlines road segments and
    /// junction; every template draws lanes and a boundary.
    #[test]
    fn layers_nest_on_every_template(
        t in 0usize..6, lanes in 1u32..4, width in 3.0f64..4.0, cw in any::<bool>(), sw in any::<bool>(),
        shoulder in prop_oneof![Just(0.0), Just(1.5)], x in -20.0f64..20.0, yaw in -3.1f64..3.1,
    ) {
        let r = road(TEMPLATES[t], lanes, width, cw, sw, shoulder);
        let map = rocc::road::build(&r);
        let bev = rasterize(&map, Pose { x, y: 0.0, yaw }, &[]);
        let drivable = [CH_DRIVABLE, CH_INTERSECTIONS, CH_ROAD_SEGMENTS];
        let lanes_px = plane(&bev, CH_LANE_GROUPS).iter().filter(|&&v| v != 0).count();
        prop_assert!(lanes_px > 0, "{:?}: no lane group pixels", r.template);
        let out = outside(&bev, CH_LANE_GROUPS, &drivable);
        prop_assert!(out == 0, "{:?}: {out} lane px off the drivable area", r.template);
        let cw_px = plane(&bev, CH_CROSSWALKS).iter().filter(|&&v| v != 0).count();
        let out = outside(&bev, CH_CROSSWALKS, &drivable);
        prop_assert!(out == 0, "{:?}: {out} of {cw_px} crosswalk px off the drivable area", r.template);
        prop_assert!(plane(&bev, CH_BOUNDARY).iter().any(|&v| v != 0), "{:?}: no boundary", r.template);
        // Walkways are beside the road, not on it: they may share the kerb's pixel row (both
        // fills include their edge, as cv2.fillPoly does) but not reach into a lane's interior.
        let on_lanes = plane(&bev, CH_WALKWAYS)
            .indexed_iter()
            .filter(|&((i, j), &v)| v != 0 && interior(&bev, CH_LANE_GROUPS, i, j))
            .count();
        // (Curved edges are sampled polylines on both sides: a stray pixel where they cross.)
        let walk = plane(&bev, CH_WALKWAYS).iter().filter(|&&v| v != 0).count();
        prop_assert!(on_lanes * 500 <= walk, "{:?}: walkway inside lanes ({on_lanes} of {walk} px)", r.template);
    }
}

/// A quarter turn of ego and world together changes nothing: seen from the junction centre
/// facing each arm in turn, a four-way junction looks the same.
#[test]
fn four_way_and_roundabout_look_the_same_from_every_arm() {
    for t in [Template::FourWay, Template::Roundabout] {
        let map = rocc::road::build(&road(t, 2, 3.5, true, true, 0.0));
        let first = rasterize(&map, Pose { x: 0.0, y: 0.0, yaw: 0.0 }, &[]);
        for q in 1..4 {
            let b = rasterize(&map, Pose { x: 0.0, y: 0.0, yaw: q as f64 * std::f64::consts::FRAC_PI_2 }, &[]);
            for (ch, name) in MASK_NAMES.iter().enumerate() {
                let (a, c) = (plane(&first, ch), plane(&b, ch));
                let n = a.iter().filter(|&&v| v != 0).count();
                // Rounding at exact half pixels differs under rotation: compare within a pixel.
                let diff = unmatched(a, c) + unmatched(c, a);
                assert!(diff * 100 <= n.max(100), "{t:?} q{q} {name}: {diff} of {n} px unmatched");
            }
        }
    }
}

/// A straight road seen from its centre facing east or west is mirrored about the centre.
#[test]
fn straight_road_is_symmetric_end_to_end() {
    let map = rocc::road::build(&road(Template::Straight, 3, 3.5, false, true, 1.0));
    let east = rasterize(&map, Pose { x: 0.0, y: 0.0, yaw: 0.0 }, &[]);
    let west = rasterize(&map, Pose { x: 0.0, y: 0.0, yaw: std::f64::consts::PI }, &[]);
    for ch in [CH_DRIVABLE, CH_LANE_GROUPS, CH_WALKWAYS, CH_BOUNDARY] {
        let n = plane(&east, ch).iter().filter(|&&v| v != 0).count();
        let diff = unmatched(plane(&east, ch), plane(&west, ch)) + unmatched(plane(&west, ch), plane(&east, ch));
        assert!(diff * 100 <= n.max(100), "{}: {diff} of {n} px unmatched", MASK_NAMES[ch]);
    }
}

/// Per-channel pixel counts and a 50 x 50 thumbnail (8 x 8 px per character, forward up): the
/// highest-priority layer present in the cell wins.
fn summary(b: &Bev) -> String {
    let mut out = String::new();
    for (ch, name) in MASK_NAMES.iter().enumerate() {
        let _ = writeln!(out, "{ch:>2} {name:<24} {:>6}", plane(b, ch).iter().filter(|&&v| v != 0).count());
    }
    let _ = writeln!(out, "   {:<24} {:>6}", "structure", b.structure.iter().filter(|&&v| v != 0).count());
    let layers: [(char, Option<usize>); 16] = [
        ('V', Some(CH_VEHICLE)),
        ('B', Some(CH_BICYCLE)),
        ('P', Some(CH_PEDESTRIAN)),
        ('C', Some(CH_TRAFFIC_CONE)),
        ('X', Some(CH_BARRIER)),
        ('S', Some(CH_CZONE_SIGN)),
        ('O', Some(CH_GENERIC_OBJECT)),
        ('T', None),
        ('=', Some(CH_CROSSWALKS)),
        ('-', Some(CH_DIVIDER)),
        ('#', Some(CH_BOUNDARY)),
        ('+', Some(CH_INTERSECTIONS)),
        (':', Some(CH_WALKWAYS)),
        ('o', Some(CH_CARPARKS)),
        ('.', Some(CH_LANE_GROUPS)),
        (',', Some(CH_DRIVABLE)),
    ];
    const CELL: usize = 8;
    for r in 0..GRID / CELL {
        let i0 = GRID - (r + 1) * CELL; // forward (+x) up
        let mut line = String::new();
        for c in 0..GRID / CELL {
            let j0 = GRID - (c + 1) * CELL; // left (+y) on the left
            let any = |l: Option<usize>| {
                (i0..i0 + CELL).any(|i| {
                    (j0..j0 + CELL).any(|j| match l {
                        Some(ch) => b.masks[[ch, i, j]] != 0,
                        None => b.structure[[i, j]] != 0,
                    })
                })
            };
            line.push(layers.iter().find(|(_, l)| any(*l)).map_or(' ', |(c, _)| *c));
        }
        out += line.trim_end();
        out.push('\n');
    }
    out
}

#[test]
fn every_example_frame_0_matches_its_raster_snapshot() {
    for dir in [root().join("scenarios"), root().join("../shared/examples")] {
        let origin = if dir.ends_with("scenarios") { "lib" } else { "shared" };
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .expect("read dir")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "scn"))
            .collect();
        files.sort();
        for path in files {
            let mut sources = SourceMap::default();
            let s = rocc::check::check_path(&path, &mut sources).expect("checks");
            let f = front(s, None).expect("compiles");
            for &ego in &f.concrete.egos {
                let bev = rasterize(&f.map, f.tracks.poses[ego][0], &frame_boxes(&f, ego, 0));
                insta::assert_snapshot!(
                    format!("raster_{origin}_{}_{}", f.concrete.name, f.tracks.agents[ego].name),
                    summary(&bev)
                );
            }
        }
    }
}
