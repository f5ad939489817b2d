//! BEV rasters of the real road templates and of every example: layer containment, symmetry,
//! re-raster IoU and a point-in-polygon boundary reference per template, and a snapshot per example clip of frame 0's per-channel pixel
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
        signals: None,
        kerb: Default::default(),
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
    for dir in [root().join("scenarios"), root().join("tests/fixtures/examples")] {
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

/// Re-rasterising the same map, ego and boxes gives IoU 1.0 in every channel, on every template,
/// also through a reused rasterizer whose buffers hold another template's frame.
#[test]
fn rerasterising_gives_iou_1_on_every_template() {
    use rocc::check::scenario::Class;
    use rocc::raster::Rasterizer;
    use rocc::view::EgoBox;
    let classes = Class::ALL.map(|(_, c)| c);
    let boxes: Vec<EgoBox> = (0..20)
        .map(|k| {
            let (l, w) = if k % 3 == 0 { (0.6, 0.6) } else { (4.5, 1.9) };
            EgoBox {
                agent: format!("a{k}"),
                kind: "k".into(),
                class: classes[k % classes.len()],
                track: k as u32,
                x: -40.0 + 4.3 * k as f64,
                y: (k % 5) as f64 * 3.1 - 6.0,
                z: 0.8,
                l,
                w,
                h: 1.6,
                yaw: 0.37 * k as f64 - 3.0,
            }
        })
        .collect();
    let mut r = Rasterizer::new();
    let mut reused = Bev::zeros();
    for (n, &t) in TEMPLATES.iter().enumerate() {
        let map = rocc::road::build(&road(t, 2, 3.5, true, true, 1.0));
        let ego = Pose { x: 3.0, y: -2.0, yaw: 0.3 };
        let fresh = rasterize(&map, ego, &boxes);
        // Dirty the reused buffers with the previous template's map seen from elsewhere.
        let other = rocc::road::build(&road(TEMPLATES[(n + 5) % 6], 3, 3.2, false, true, 0.0));
        r.rasterize_into(&other, Pose { x: -7.0, y: 5.0, yaw: 2.0 }, &boxes[3..], &mut reused);
        r.rasterize_into(&map, ego, &boxes, &mut reused);
        for (k, b) in [rasterize(&map, ego, &boxes), reused.clone()].iter().enumerate() {
            for (ch, name) in MASK_NAMES.iter().enumerate() {
                let (pa, pb) = (plane(&fresh, ch), plane(b, ch));
                let inter = pa.iter().zip(pb.iter()).filter(|(x, y)| **x != 0 && **y != 0).count();
                let union = pa.iter().zip(pb.iter()).filter(|(x, y)| **x != 0 || **y != 0).count();
                assert_eq!(inter, union, "{t:?} run {k} {name}: IoU {inter}/{union}");
            }
            assert_eq!(fresh.aux, b.aux, "{t:?} run {k}: aux");
            assert_eq!(fresh.structure, b.structure, "{t:?} run {k}: structure");
        }
        // The boxes are on the canvas: the agent channels are not trivially empty.
        assert!(
            plane(&fresh, CH_VEHICLE).iter().any(|&v| v != 0) && plane(&fresh, CH_PEDESTRIAN).iter().any(|&v| v != 0)
        );
    }
}

/// A t_junction is mirror-symmetric about its stem (x = 0). Seen from the junction centre looking
/// down the stem, the world mirror x -> -x is the ego mirror y -> -y, which maps pixel column j to
/// 400 - j (u = 4 y + 200). Every map channel must equal its mirror pixel for pixel: the layout
/// is mirror-exact in floating point, and no vertex here lands on an exact half pixel (where
/// round-half-away would break the tie the same way on both sides). Lane directions differ under
/// the mirror (right-hand traffic), but no map channel encodes direction, and there are no boxes.
#[test]
fn t_junction_is_mirror_symmetric_about_its_stem() {
    let map = rocc::road::build(&road(Template::TJunction, 2, 3.5, true, true, 1.5));
    for ego in [
        Pose { x: 0.0, y: 0.0, yaw: -std::f64::consts::FRAC_PI_2 },
        Pose { x: 0.0, y: -12.0, yaw: std::f64::consts::FRAC_PI_2 },
    ] {
        let b = rasterize(&map, ego, &[]);
        let map_channels = [
            CH_INTERSECTIONS,
            CH_DRIVABLE,
            CH_WALKWAYS,
            CH_CROSSWALKS,
            CH_LANE_GROUP_CONNECTORS,
            CH_LANE_GROUPS,
            CH_ROAD_SEGMENTS,
            CH_DIVIDER,
            CH_PED_CROSSING,
            CH_BOUNDARY,
        ];
        for ch in map_channels {
            let p = plane(&b, ch);
            let mirrored =
                ndarray::Array2::from_shape_fn((GRID, GRID), |(i, j)| if j == 0 { 0 } else { p[[i, GRID - j]] });
            // Column 0 has no mirror image on the canvas.
            let mut orig = p.to_owned();
            orig.column_mut(0).fill(0);
            let n = orig.iter().filter(|&&v| v != 0).count();
            let exact = orig.iter().zip(mirrored.iter()).filter(|(a, c)| a != c).count();
            assert!(n > 0, "{}: empty", MASK_NAMES[ch]);
            assert!(exact == 0, "{} from {ego:?}: {exact} of {n} px differ from the mirror", MASK_NAMES[ch]);
        }
    }
}

/// Ch 17 against an independent reference: each pixel centre is taken back to the world and
/// tested point-in-polygon against the map's plain road-segment and junction polygons (no fill,
/// no rounding, no shared code with the rasteriser); the reference outline is the pixels of that
/// union with a 4-neighbour outside it (the canvas border is not an edge, SPEC.md). The
/// rasteriser fills cv2-style on rounded vertices, so its edges may sit one pixel off the exact
/// ones (cv2 includes both edges of a span, so the raster's outline mostly sits one pixel outside
/// the exact one): every outline pixel of either must have one of the other within one pixel, and
/// none may be further (gaps between adjacent polygons or a missing layer would be).
#[test]
fn boundary_matches_a_point_in_polygon_reference_on_every_template() {
    use rocc::geom::point_in_polygon;
    for (n, &t) in TEMPLATES.iter().enumerate() {
        let map = rocc::road::build(&road(t, 2, 3.5, true, true, 1.0));
        let ego = Pose { x: 4.0 - n as f64, y: -3.0 + n as f64, yaw: 0.35 + 0.4 * n as f64 };
        let bev = rasterize(&map, ego, &[]);
        let polys: Vec<(glam::DVec2, glam::DVec2, &Vec<glam::DVec2>)> = map
            .road_segments
            .iter()
            .chain(&map.intersections)
            .map(|p| {
                let lo = p.iter().fold(glam::DVec2::INFINITY, |a, q| a.min(*q));
                let hi = p.iter().fold(glam::DVec2::NEG_INFINITY, |a, q| a.max(*q));
                (lo, hi, p)
            })
            .collect();
        let (c, s) = (ego.yaw.cos(), ego.yaw.sin());
        let road = ndarray::Array2::from_shape_fn((GRID, GRID), |(i, j)| {
            let (x, y) = ((i as f64 - 200.0) * RES, (j as f64 - 200.0) * RES);
            let w = glam::DVec2::new(ego.x + c * x - s * y, ego.y + s * x + c * y);
            polys.iter().any(|(lo, hi, p)| w.cmpge(*lo).all() && w.cmple(*hi).all() && point_in_polygon(w, p))
        });
        let reference = ndarray::Array2::from_shape_fn((GRID, GRID), |(i, j)| {
            let out = |a: i64, b: i64| {
                (0..GRID as i64).contains(&a) && (0..GRID as i64).contains(&b) && !road[[a as usize, b as usize]]
            };
            let (a, b) = (i as i64, j as i64);
            i8::from(road[[i, j]] && (out(a - 1, b) || out(a + 1, b) || out(a, b - 1) || out(a, b + 1)))
        });
        let got = plane(&bev, CH_BOUNDARY);
        let n_ref = reference.iter().filter(|&&v| v != 0).count();
        let n_got = got.iter().filter(|&&v| v != 0).count();
        assert!(n_ref > 400, "{t:?}: a non-trivial outline ({n_ref} px)");
        let (missing, extra) = (unmatched(reference.view(), got), unmatched(got, reference.view()));
        assert!(
            missing == 0 && extra == 0,
            "{t:?}: {missing} reference px and {extra} raster px unmatched ({n_ref} / {n_got})"
        );
        // Within one pixel is not enough on its own: a thicker outline (an 8-neighbour rule) still
        // lies within a pixel of the right one. The outline's length in pixels must agree too;
        // vertex rounding and the inclusive fill shift it by a pixel but change its pixel count by
        // a few per cent at most (3.3 % on the curve, under 0.5 % elsewhere).
        let d = n_got.abs_diff(n_ref);
        assert!(d * 20 <= n_ref, "{t:?}: outline of {n_got} px against {n_ref} px in the reference");
    }
}
