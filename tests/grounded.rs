//! The learned backend's parts: the splat against a brute-force dense reference, gradients by
//! finite differences, the fused head, shapes, padding invariance, checkpoint round trips (.bpk,
//! safetensors) and the weights diagnostics. The losses are in `grounded_loss.rs`.

#[path = "support/tmp.rs"]
mod tmp;

use burn::nn::transformer::TransformerEncoderInput;
use burn::prelude::*;
use ndarray::Array3;
use rocc::backend::grounded::config::GroundedConfig;
use rocc::backend::grounded::latents::{self, Anchor, GBox};
use rocc::backend::grounded::model::{Autoencoder, Generator, HostBatch};
use rocc::backend::grounded::splat::{ActiveAnchors, PARAMS, Region, activate, splat};
use rocc::backend::grounded::{Grounded, cpu, load_weights, save_safetensors};
use rocc::backend::layout::{BACKGROUND, N_LABELS, NX, NY, NZ, PEDESTRIAN, VEHICLE};
use rocc::raster::layout::{CH_DRIVABLE, GRID, N_AUX, N_MASKS};
use rocc::sample::Rng;

#[path = "support/grounded_tiny.rs"]
mod grounded_tiny;
pub use grounded_tiny::tiny;

fn raw_params(n: usize, seed: u64) -> Vec<f32> {
    let mut r = Rng::new(seed);
    (0..n * PARAMS).map(|_| (r.normal() * 0.8) as f32).collect()
}

/// f64 host version of `activate` + the windowed splat: the reference both tests compare with.
struct RefGauss {
    mean: [f64; 3],
    scale: [f64; 3],
    rot: [f64; 9],
    opacity: f64,
    feat: [f64; N_LABELS],
    batch: usize,
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

fn activate_ref(raw: &[f64], a: &ActiveAnchors, bound: f64, smin: f64, smax: f64) -> Vec<RefGauss> {
    (0..a.pos.len())
        .map(|n| {
            let p = &raw[n * PARAMS..(n + 1) * PARAMS];
            let (c, s) = (a.cos[n] as f64, a.sin[n] as f64);
            let o: Vec<f64> = (0..3).map(|i| p[i].tanh() * bound).collect();
            let mean = [
                a.pos[n][0] as f64 + c * o[0] - s * o[1],
                a.pos[n][1] as f64 + s * o[0] + c * o[1],
                a.pos[n][2] as f64 + o[2],
            ];
            let scale = [0, 1, 2].map(|i| smin + (smax - smin) * sigmoid(p[3 + i]));
            let q = [p[6] + 1.0, p[7], p[8], p[9]];
            let norm = (q.iter().map(|v| v * v).sum::<f64>() + 1e-8).sqrt();
            let [w, x, y, z] = q.map(|v| v / norm);
            let rq = [
                [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
                [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
                [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
            ];
            let mut rot = [0.0; 9];
            for j in 0..3 {
                rot[j] = c * rq[0][j] - s * rq[1][j];
                rot[3 + j] = s * rq[0][j] + c * rq[1][j];
                rot[6 + j] = rq[2][j];
            }
            RefGauss {
                mean,
                scale,
                rot,
                opacity: sigmoid(p[10]),
                feat: std::array::from_fn(|k| p[11 + k]),
                batch: a.batch[n],
            }
        })
        .collect()
}

/// Brute force: every voxel of the region against every Gaussian; `window` = None evaluates
/// the untruncated Gaussian everywhere.
fn dense_ref(gs: &[RefGauss], region: Region, batch: usize, window: Option<i64>) -> Vec<f64> {
    let mut out = vec![0.0; batch * region.voxels() * N_LABELS];
    for b in 0..batch {
        for li in 0..region.ni {
            for lj in 0..region.nj {
                for k in 0..NZ {
                    let (i, j) = (region.i0 + li, region.j0 + lj);
                    let v = b * region.voxels() + (li * region.nj + lj) * NZ + k;
                    for g in gs.iter().filter(|g| g.batch == b) {
                        let c = g.mean.map(|m| m.floor() as i64);
                        if let Some(r) = window
                            && ((i as i64 - c[0]).abs() > r
                                || (j as i64 - c[1]).abs() > r
                                || (k as i64 - c[2]).abs() > r)
                        {
                            continue;
                        }
                        let d = [i as f64 + 0.5 - g.mean[0], j as f64 + 0.5 - g.mean[1], k as f64 + 0.5 - g.mean[2]];
                        let mut m = 0.0;
                        for a in 0..3 {
                            let u = d[0] * g.rot[a] + d[1] * g.rot[3 + a] + d[2] * g.rot[6 + a];
                            m += (u / g.scale[a]).powi(2);
                        }
                        let w = g.opacity * (-0.5 * m).exp();
                        for c in 0..N_LABELS {
                            out[v * N_LABELS + c] += w * g.feat[c];
                        }
                    }
                }
            }
        }
    }
    out
}

/// Anchors for a tiny splat case: two Gaussians in batch 0 (one near the region's edge, so its
/// window is clipped), one in batch 1, one at the top of the grid (clipped in z).
fn case() -> (ActiveAnchors, Region) {
    let region = Region { i0: 100, j0: 200, ni: 10, nj: 9 };
    let mut a = ActiveAnchors::default();
    for (pos, yaw, b) in [
        ([104.3f32, 204.6, 14.2], 0.3f32, 0usize),
        ([100.2, 207.7, 10.6], -1.2, 0),
        ([106.4, 202.3, 20.4], 2.0, 1),
        ([103.6, 203.3, 31.4], 0.0, 1),
    ] {
        a.pos.push(pos);
        a.cos.push(yaw.cos());
        a.sin.push(yaw.sin());
        a.batch.push(b);
    }
    (a, region)
}

const BOUND: f32 = 1.5;
const SMIN: f32 = 0.25;
const WINDOW: usize = 2;

#[test]
fn splat_matches_a_brute_force_dense_reference() {
    let device = cpu();
    let (a, region) = case();
    let raw = raw_params(a.pos.len(), 1);
    let smax = WINDOW as f32 / 3.0;
    let t = Tensor::<2>::from_data(TensorData::new(raw.clone(), [a.pos.len(), PARAMS]), &device);
    let g = activate(t, &a, BOUND, SMIN, smax);
    let got: Vec<f32> = splat(&g, region, 2, WINDOW).to_data().iter::<f32>().collect();
    let raw64: Vec<f64> = raw.iter().map(|&v| v as f64).collect();
    let gs = activate_ref(&raw64, &a, BOUND as f64, SMIN as f64, smax as f64);
    let want = dense_ref(&gs, region, 2, Some(WINDOW as i64));
    assert_eq!(got.len(), want.len());
    let mut max_err = 0.0f64;
    for (g, w) in got.iter().zip(&want) {
        max_err = max_err.max((*g as f64 - w).abs());
    }
    assert!(max_err < 1e-4, "windowed splat differs from the dense reference by {max_err}");
    // The window loses little: the untruncated Gaussians differ by at most exp(-4.5) of their peak
    // mass per voxel, so the totals agree within a few percent.
    let full = dense_ref(&gs, region, 2, None);
    let (sa, sf): (f64, f64) = (want.iter().map(|v| v.abs()).sum(), full.iter().map(|v| v.abs()).sum());
    assert!(sa > 0.1, "the case must put mass in the region");
    assert!((sa - sf).abs() / sf < 0.05, "window keeps {sa} of {sf}");
    // Geometry bounds: offsets within the bound of the anchor, rotations orthonormal.
    for (g, n) in gs.iter().zip(0..) {
        let (c, s) = (a.cos[n] as f64, a.sin[n] as f64);
        let d = [g.mean[0] - a.pos[n][0] as f64, g.mean[1] - a.pos[n][1] as f64, g.mean[2] - a.pos[n][2] as f64];
        let local = [c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]];
        assert!(local.iter().all(|v| v.abs() <= BOUND as f64 + 1e-9), "{local:?}");
        assert!(g.scale.iter().all(|&s| s >= SMIN as f64 && s <= smax as f64));
        for p in 0..3 {
            for q in 0..3 {
                let dot: f64 = (0..3).map(|r| g.rot[3 * r + p] * g.rot[3 * r + q]).sum();
                assert!((dot - (p == q) as u8 as f64).abs() < 1e-6);
            }
        }
    }
}

#[test]
fn splat_gradients_match_finite_differences() {
    let device = cpu().autodiff();
    let (a, region) = case();
    let n = a.pos.len();
    let smax = WINDOW as f32 / 3.0;
    let raw = raw_params(n, 2);
    let mut r = Rng::new(9);
    let weights: Vec<f64> = (0..2 * region.voxels() * N_LABELS).map(|_| r.normal()).collect();
    let t = Tensor::<2>::from_data(TensorData::new(raw.clone(), [n, PARAMS]), &device).require_grad();
    let w = Tensor::<2>::from_data(
        TensorData::new(weights.iter().map(|&v| v as f32).collect::<Vec<_>>(), [2 * region.voxels(), N_LABELS]),
        &device,
    );
    let loss = (splat(&activate(t.clone(), &a, BOUND, SMIN, smax), region, 2, WINDOW) * w).sum();
    let grads = loss.backward();
    let got: Vec<f32> = t.grad(&grads).expect("raw params get a gradient").to_data().iter::<f32>().collect();
    let f = |p: &[f64]| -> f64 {
        let gs = activate_ref(p, &a, BOUND as f64, SMIN as f64, smax as f64);
        dense_ref(&gs, region, 2, Some(WINDOW as i64)).iter().zip(&weights).map(|(x, y)| x * y).sum()
    };
    let base: Vec<f64> = raw.iter().map(|&v| v as f64).collect();
    // The means must sit away from voxel faces so a step never changes the window.
    for g in activate_ref(&base, &a, BOUND as f64, SMIN as f64, smax as f64) {
        assert!(g.mean.iter().all(|m| (m - m.floor()) > 0.01 && (m - m.floor()) < 0.99), "{:?}", g.mean);
    }
    let names = ["offset", "offset", "offset", "scale", "scale", "scale", "rot", "rot", "rot", "rot", "opacity"];
    let eps = 1e-6;
    let mut checked = 0;
    for row in 0..n {
        for c in 0..PARAMS {
            let i = row * PARAMS + c;
            let (mut hi, mut lo) = (base.clone(), base.clone());
            hi[i] += eps;
            lo[i] -= eps;
            let fd = (f(&hi) - f(&lo)) / (2.0 * eps);
            let ad = got[i] as f64;
            let what = names.get(c).copied().unwrap_or("feature");
            assert!(
                (fd - ad).abs() <= 2e-3 * fd.abs().max(1.0),
                "d loss / d {what}[{row}][{c}]: autodiff {ad}, finite difference {fd}"
            );
            checked += (fd.abs() > 1e-3) as usize;
        }
    }
    assert!(checked > n * 8, "most parameters must matter in this case ({checked})");
}

#[test]
fn fused_head_matches_the_tensor_formulation() {
    use rocc::backend::grounded::head::{head, head_tensor_ops};
    let device = cpu().autodiff();
    let mut rng = Rng::new(9);
    let nv = 3 * 1100 * NZ;
    let mut rand = |n: usize, s: f64| -> Vec<f32> { (0..n).map(|_| (rng.normal() * s) as f32).collect() };
    let (splat, bias, r, w) =
        (rand(nv * N_LABELS, 3.0), rand(NZ * N_LABELS, 1.0), rand(nv, 2.0), rand(nv * N_LABELS, 1.0));
    let run = |fused: bool| -> [Vec<f32>; 4] {
        let t = |v: &Vec<f32>, shape: [usize; 2]| Tensor::<2>::from_data(TensorData::new(v.clone(), shape), &device);
        let (s, b, rr) = (
            t(&splat, [nv, N_LABELS]).require_grad(),
            t(&bias, [NZ, N_LABELS]).require_grad(),
            t(&r, [nv, 1]).require_grad(),
        );
        let out = if fused {
            head(s.clone(), b.clone(), rr.clone())
        } else {
            head_tensor_ops(s.clone(), b.clone(), rr.clone())
        };
        let grads = (out.clone() * t(&w, [nv, N_LABELS])).sum().backward();
        let host = |x: Tensor<2>| x.to_data().iter::<f32>().collect::<Vec<_>>();
        [host(out), host(s.grad(&grads).unwrap()), host(b.grad(&grads).unwrap()), host(rr.grad(&grads).unwrap())]
    };
    // Without autodiff (inference) the very same bits.
    let plain = |fused: bool| -> Vec<f32> {
        let t = |v: &Vec<f32>, shape: [usize; 2]| Tensor::<2>::from_data(TensorData::new(v.clone(), shape), &cpu());
        let (s, b, rr) = (t(&splat, [nv, N_LABELS]), t(&bias, [NZ, N_LABELS]), t(&r, [nv, 1]));
        let out = if fused { head(s, b, rr) } else { head_tensor_ops(s, b, rr) };
        out.to_data().iter::<f32>().collect()
    };
    assert!(plain(true) == plain(false), "inference logits differ from the tensor formulation's");
    let (ours, reference) = (run(true), run(false));
    for (name, i) in [("logits", 0), ("splat", 1), ("bias", 2), ("residual", 3)] {
        let scale = reference[i].iter().fold(1e-6f32, |m, x| m.max(x.abs()));
        let err = ours[i].iter().zip(&reference[i]).fold(0f32, |m, (a, b)| m.max((a - b).abs())) / scale;
        assert!(err < 1e-5, "the gradient of the {name} differs by {err} of its largest element");
    }
}

/// The largest magnitude of `reference`, and the largest difference of `a` from it relative to
/// that.
fn rel(a: &[f32], reference: &[f32]) -> (f32, f32) {
    let scale = reference.iter().fold(0f32, |m, x| m.max(x.abs()));
    (scale, a.iter().zip(reference).fold(0f32, |m, (x, y)| m.max((x - y).abs())) / scale)
}

fn bev_with_road() -> (Array3<i8>, Array3<i32>) {
    let mut masks = Array3::<i8>::zeros((N_MASKS, GRID, GRID));
    // A 10 m wide road along x.
    masks.slice_mut(ndarray::s![CH_DRIVABLE, .., 180..220]).fill(1);
    (masks, Array3::zeros((N_AUX, GRID, GRID)))
}

fn car(x: f64, y: f64, l: f64) -> GBox {
    GBox { label: VEHICLE, x, y, z: 0.8, l, w: 1.9, h: 1.6, yaw: 0.4 }
}

#[test]
fn latent_set_shapes() {
    let cfg = tiny();
    let (masks, _) = bev_with_road();
    let boxes = [
        car(5.0, 0.0, 3.9),
        car(-20.0, 2.0, 12.0),
        GBox { label: PEDESTRIAN, x: 3.0, y: 8.0, z: 0.9, l: 0.6, w: 0.6, h: 1.8, yaw: 0.0 },
    ];
    let set = latents::build(&cfg, &boxes, &masks);
    let fg: Vec<&Anchor> = set.iter().filter(|a| a.foreground).collect();
    // Longer than `split_length_m` (4 m) splits: the 12 m bus into 3 pieces of 4 m along its
    // heading; the 3.9 m car and the pedestrian stay whole.
    assert_eq!(fg.len(), 5);
    let bus: Vec<&&Anchor> = fg.iter().filter(|a| (a.ext[0] - 4.0).abs() < 1e-9).collect();
    assert_eq!(bus.len(), 3);
    let mid = bus.iter().map(|a| a.pos[0]).sum::<f64>() / 3.0;
    assert!((mid + 20.0).abs() < 1e-9);
    // Foreground nearest the ego first.
    assert_eq!(fg[0].label, VEHICLE);
    assert!((fg[0].pos[0] - 5.0).abs() < 1e-9);
    // Background only over the road's footprint (|y| <= 5 m, cells of 10 m).
    let bg: Vec<&Anchor> = set.iter().filter(|a| !a.foreground).collect();
    assert!(!bg.is_empty());
    assert!(bg.iter().all(|a| a.label == BACKGROUND && a.pos[1].abs() <= 10.0), "{bg:?}");
    assert!(set.len() <= cfg.latents);
    assert_eq!(latents::budget(&cfg, VEHICLE), 6);
    assert_eq!(latents::budget(&cfg, PEDESTRIAN), 3);
    // Capacity: Q caps the set, foreground kept first.
    let mut small = cfg.clone();
    small.latents = 6;
    small.max_foreground = 4;
    let capped = latents::build(&small, &boxes, &masks);
    assert_eq!(capped.len(), 6);
    assert_eq!(capped.iter().filter(|a| a.foreground).count(), 4);
}

#[test]
fn model_shapes_and_padding_invariance() {
    let cfg = tiny();
    let device = cpu();
    let (masks, aux) = bev_with_road();
    let a = latents::build(&cfg, &[car(5.0, 0.0, 4.5)], &masks);
    let b = latents::build(&cfg, &[car(-3.0, 1.0, 4.0), car(10.0, -2.0, 5.0)], &masks);
    let region = Region { i0: 180, j0: 180, ni: 40, nj: 40 };
    let hb = HostBatch::new(vec![a.clone(), b.clone()]);
    assert_eq!(hb.q, a.len().max(b.len()));
    assert_eq!(hb.pad.iter().filter(|&&p| !p).count(), a.len() + b.len());
    let g = Generator::new(&cfg, &device);
    let bev = rocc::backend::grounded::model::bev_batch(&[(&masks, &aux)]);
    let bev2 = [bev.clone(), bev.clone()].concat();
    let out = g.forward(bev2, &hb, region);
    assert_eq!(out.logits.dims(), [2 * region.voxels(), N_LABELS]);
    assert_eq!(out.background.as_ref().map(|t| t.dims()), Some([2 * region.voxels(), 1]));
    // The zero-initialised background head adds nothing at first.
    assert_eq!(out.background.unwrap().abs().max().into_scalar::<f32>(), 0.0);
    // Padding further changes nothing: frame `a` alone (q = |a|) vs in the padded batch.
    let alone = g.forward(bev.clone(), &HostBatch::new(vec![a.clone()]), region).logits;
    let batched = out.logits.slice([0..region.voxels(), 0..N_LABELS]);
    let diff = (alone - batched).abs().max().into_scalar::<f32>();
    assert!(diff < 1e-4, "padding changed the logits by {diff}");
    let ae = Autoencoder::new(&cfg, &device);
    let labels = Array3::<u8>::zeros((NX, NY, NZ));
    let enc = Autoencoder::encoder_input(&cfg, &hb, &[&labels, &labels]);
    assert_eq!(enc.len(), 2 * hb.q * 12 * N_LABELS);
    let o = ae.forward(enc, &hb, region, None);
    assert_eq!(o.logits.dims(), [2 * region.voxels(), N_LABELS]);
    assert_eq!(o.mu.dims(), [a.len() + b.len(), cfg.latent_dim]);
    // A whole-grid prediction has the occupancy layout.
    let pred = Grounded::from_model(cfg.clone(), g, "t").predict(&[car(5.0, 0.0, 4.5)], &masks, &aux);
    assert_eq!(pred.dim(), (NX, NY, NZ));
    assert!(pred.iter().all(|&l| (l as usize) < N_LABELS));
}

/// A training batch gets the logits of its frames alone and, for a loss summed over its frames,
/// the gradients of their losses summed, and every real latent gets the Gaussians of burn's
/// transformer over the padded batch: each latent set attends within itself alone at its own
/// length (`Decoder::raw`), padding changes nothing, an empty set included.
#[test]
fn a_batch_gets_the_values_and_gradients_of_its_frames_alone() {
    let cfg = tiny();
    let device = cpu().autodiff();
    let (masks, aux) = bev_with_road();
    let sets = vec![
        latents::build(&cfg, &[car(5.0, 0.0, 4.5), car(-30.0, 1.0, 12.0)], &masks),
        Vec::new(),
        latents::build(&cfg, &[car(-3.0, 1.0, 4.0)], &Array3::zeros((N_MASKS, GRID, GRID))),
        latents::build(&cfg, &[], &masks),
    ];
    let lens: Vec<usize> = sets.iter().map(Vec::len).collect();
    assert!(lens[0] > lens[3] && lens[3] > lens[2] && lens[2] > 0, "sets of distinct lengths: {lens:?}");
    let g = Generator::new(&cfg, &device);
    let region = Region { i0: 150, j0: 150, ni: 100, nj: 100 };
    let per = region.voxels() * N_LABELS;
    let mut rng = Rng::new(11);
    let w: Vec<f32> = (0..sets.len() * per).map(|_| rng.normal() as f32).collect();
    // Logits and the gradients of sum(logits * w) for the frames `which`, in one batch.
    let run = |which: &[usize]| {
        let hb = HostBatch::new(which.iter().map(|&i| sets[i].clone()).collect());
        let bev = rocc::backend::grounded::model::bev_batch(&vec![(&masks, &aux); which.len()]);
        let logits = g.forward(bev, &hb, region).logits;
        let wt: Vec<f32> = which.iter().flat_map(|&i| w[i * per..(i + 1) * per].iter().copied()).collect();
        let wt = Tensor::<2>::from_data(TensorData::new(wt, [which.len() * region.voxels(), N_LABELS]), &device);
        let grads = (logits.clone() * wt).sum().backward();
        // None where nothing reaches the parameter (the empty set has no Gaussian).
        let host = |t: Option<Tensor<2>>| t.map(|t| t.to_data().iter::<f32>().collect::<Vec<f32>>());
        let layer = &g.decoder.transformer.layers[0];
        let grads = [
            host(layer.mha.query.weight.val().grad(&grads)),
            host(layer.pwff.linear_inner.weight.val().grad(&grads)),
            host(g.decoder.input.weight.val().grad(&grads)),
            host(g.decoder.head.weight.val().grad(&grads)),
            host(g.cond1.weight.val().grad(&grads)),
        ];
        (logits.to_data().iter::<f32>().collect::<Vec<f32>>(), grads)
    };
    let (batch, batch_grads) = run(&[0, 1, 2, 3]);
    let mut summed: Vec<Vec<f32>> = vec![Vec::new(); batch_grads.len()];
    for i in 0..sets.len() {
        let (alone, grads) = run(&[i]);
        let (_, err) = rel(&batch[i * per..(i + 1) * per], &alone);
        assert!(err < 1e-5, "frame {i}: its logits in the batch differ by {err} of the largest");
        for (s, g) in summed.iter_mut().zip(grads.into_iter().flatten()) {
            if s.is_empty() {
                *s = g;
            } else {
                s.iter_mut().zip(g).for_each(|(s, g)| *s += g);
            }
        }
    }
    // Against burn's transformer over the padded batch with the padding masked: every real
    // latent's Gaussians.
    let d = &g.decoder;
    let hb = HostBatch::new(sets.clone());
    let (b, q, gs) = (hb.b(), hb.q, cfg.max_gaussians());
    let z: Vec<f32> = (0..b * q * cfg.latent_dim).map(|_| rng.normal() as f32).collect();
    let z = Tensor::<3>::from_data(TensorData::new(z, [b, q, cfg.latent_dim]), &device);
    let ours: Vec<f32> = d.raw(z.clone(), &hb).to_data().iter::<f32>().collect();
    let x = d.input.forward(Tensor::cat(vec![z, hb.feats_tensor(&device)], 2));
    let y = d.transformer.forward(TransformerEncoderInput::new(x).mask_pad(hb.pad_tensor(&device)));
    let reference: Vec<f32> = d.head.forward(y).to_data().iter::<f32>().collect();
    let cols = gs * PARAMS;
    // Ours holds the sets one after another, the reference each at `q` rows.
    let real = |v: &[f32], starts: &[usize]| -> Vec<f32> {
        (0..b).flat_map(|i| v[starts[i] * cols..(starts[i] + sets[i].len()) * cols].to_vec()).collect()
    };
    assert_eq!(ours.len(), hb.lens().iter().sum::<usize>() * cols, "no row for padding");
    let padded: Vec<usize> = (0..b).map(|i| i * q).collect();
    let (scale, err) = rel(&real(&ours, &hb.starts()), &real(&reference, &padded));
    assert!(scale > 0.0 && err < 1e-5, "the real latents' Gaussians differ by {err} of the largest");
    let names = ["attention query", "feed-forward", "decoder input", "decoder head", "cond1"];
    for ((name, a), b) in names.iter().zip(&batch_grads).zip(&summed) {
        let a = a.as_ref().expect("the batch's gradient");
        let (scale, err) = rel(a, b);
        assert!(scale > 0.0 && err < 1e-4, "{name}: gradients differ by {err} of the largest");
    }
}

/// The generator's input: masks 0/1, aux scaled per channel, frame after frame; a frame whose
/// arrays are short of channels or of another size reads zeros there.
#[test]
fn bev_batch_scales_each_channel_and_zeroes_what_a_frame_lacks() {
    use rocc::backend::grounded::model::{BEV_CHANNELS, bev_batch};
    let (masks, mut aux) = bev_with_road();
    aux.slice_mut(ndarray::s![6, 10..20, 30..40]).fill(-3);
    aux.slice_mut(ndarray::s![0, 0..5, 0..400]).fill(40);
    let short = masks.slice(ndarray::s![0..3, .., ..]).to_owned();
    let small = Array3::<i32>::from_elem((N_AUX, 10, 10), 5);
    let bev = bev_batch(&[(&masks, &aux), (&short, &small)]);
    let px = GRID * GRID;
    assert_eq!(bev.len(), 2 * BEV_CHANNELS * px);
    let at = |f: usize, c: usize, i: usize, j: usize| bev[(f * BEV_CHANNELS + c) * px + i * GRID + j];
    let road = masks.indexed_iter().find(|(_, v)| **v != 0).map(|(ix, _)| ix).expect("a road pixel");
    assert_eq!(at(0, road.0, road.1, road.2), 1.0);
    assert_eq!(at(1, road.0, road.1, road.2), if road.0 < 3 { 1.0 } else { 0.0 });
    assert_eq!(at(0, N_MASKS, 2, 399), 2.0, "offsets are scaled by 1/20");
    assert_eq!(at(0, N_MASKS + 6, 15, 35), -1.5, "heights by 1/2");
    assert_eq!(at(0, N_MASKS + 6, 25, 35), 0.0);
    let ones = |f: usize, c: usize| bev[(f * BEV_CHANNELS + c) * px..][..px].iter().filter(|&&v| v != 0.0).count();
    for c in 0..N_MASKS {
        let want = masks.index_axis(ndarray::Axis(0), c).iter().filter(|&&v| v != 0).count();
        assert_eq!(ones(0, c), want, "mask {c}");
        assert_eq!(ones(1, c), if c < 3 { want } else { 0 }, "frame 2, mask {c}");
    }
    assert!((N_MASKS..BEV_CHANNELS).all(|c| ones(1, c) == 0), "aux of another size reads zeros");
}

/// A training crop's logits are the whole grid's logits of its columns, and every parameter's
/// gradient agrees: the background head runs only over the crop's feature pixels (and its
/// kernel's reach, or the map's own padding at an edge), the rest of the generator over the
/// whole BEV. Two crops of odd sizes, one on the grid's first rows, one in its far corner.
#[test]
fn a_crop_gets_the_logits_and_gradients_of_the_whole_grid() {
    let cfg = tiny();
    let device = cpu().autodiff();
    let (masks, mut aux) = bev_with_road();
    aux.slice_mut(ndarray::s![0, 100..300, 150..250]).fill(7);
    let mut g = Generator::new(&cfg, &device);
    // The background head starts at zero: random weights make it speak.
    let f = cfg.bev_features();
    g.bg_out = Some(burn::nn::conv::Conv2dConfig::new([f, NZ], [1, 1]).init(&device));
    let boxes = [car(5.0, 0.0, 4.5), car(-45.0, -45.0, 4.0), car(46.0, 47.0, 3.0)];
    let hb = HostBatch::new(vec![latents::build(&cfg, &boxes, &masks)]);
    let bev = rocc::backend::grounded::model::bev_batch(&[(&masks, &aux)]);
    let crops = [Region { i0: 0, j0: 201, ni: 45, nj: 39 }, Region { i0: 371, j0: 363, ni: 29, nj: 37 }];
    let mut rng = Rng::new(4);
    let weights: Vec<Vec<f32>> =
        crops.iter().map(|r| (0..r.voxels() * N_LABELS).map(|_| rng.normal() as f32).collect()).collect();
    let w = |v: &Vec<f32>| Tensor::<2>::from_data(TensorData::new(v.clone(), [v.len() / N_LABELS, N_LABELS]), &device);
    let full = g.forward(bev.clone(), &hb, Region::full()).logits;
    let (mut crop_loss, mut full_loss) = (Tensor::<1>::zeros([1], &device), Tensor::<1>::zeros([1], &device));
    for (region, wt) in crops.iter().zip(&weights) {
        let crop = g.forward(bev.clone(), &hb, *region).logits;
        let rows: Vec<i64> = (region.i0..region.i0 + region.ni)
            .flat_map(|i| {
                (region.j0..region.j0 + region.nj)
                    .flat_map(move |j| (0..NZ).map(move |k| ((i * NY + j) * NZ + k) as i64))
            })
            .collect();
        let n = rows.len();
        let of_full = full.clone().select(0, Tensor::<1, Int>::from_data(TensorData::new(rows, [n]), &device));
        let (a, b): (Vec<f32>, Vec<f32>) =
            (crop.to_data().iter::<f32>().collect(), of_full.to_data().iter::<f32>().collect());
        assert!(a == b, "the crop's logits differ from the whole grid's");
        crop_loss = crop_loss + (crop * w(wt)).sum();
        full_loss = full_loss + (of_full * w(wt)).sum();
    }
    let (gc, gf) = (crop_loss.backward(), full_loss.backward());
    let host = |v: Vec<f32>| v;
    let g4 = |t: Tensor<4>| {
        let h = |g: Option<Tensor<4>>| host(g.expect("a gradient").to_data().iter::<f32>().collect());
        (h(t.grad(&gc)), h(t.grad(&gf)))
    };
    let g2 = |t: Tensor<2>| {
        let h = |g: Option<Tensor<2>>| host(g.expect("a gradient").to_data().iter::<f32>().collect());
        (h(t.grad(&gc)), h(t.grad(&gf)))
    };
    // Per parameter: its gradient from the crops, and from the whole grid.
    type Pair = (Vec<f32>, Vec<f32>);
    let mut pairs: Vec<(String, Pair)> =
        g.bev.convs.iter().enumerate().map(|(i, c)| (format!("bev conv {i}"), g4(c.weight.val()))).collect();
    pairs.push(("background hidden".into(), g4(g.bg_hidden.as_ref().unwrap().weight.val())));
    pairs.push(("background out".into(), g4(g.bg_out.as_ref().unwrap().weight.val())));
    pairs.push(("decoder head".into(), g2(g.decoder.head.weight.val())));
    pairs.push(("cond1".into(), g2(g.cond1.weight.val())));
    pairs.push(("layer bias".into(), g2(g.decoder.layer_bias.val())));
    for (name, (a, b)) in pairs {
        let (scale, err) = rel(&a, &b);
        assert!(scale > 0.0 && err < 1e-5, "{name}: gradients differ by {err} of the largest");
    }
}

/// A probe of a model's parameters: the logits of a small scene depend on every one of them.
fn params(g: &Generator) -> Vec<f32> {
    let (masks, aux) = bev_with_road();
    let cfg = tiny();
    let hb = HostBatch::new(vec![latents::build(&cfg, &[car(5.0, 0.0, 4.5)], &masks)]);
    let bev = rocc::backend::grounded::model::bev_batch(&[(&masks, &aux)]);
    g.forward(bev, &hb, Region { i0: 200, j0: 190, ni: 30, nj: 20 }).logits.to_data().iter::<f32>().collect()
}

#[test]
fn parameter_ids_are_distinct_and_the_same_on_every_build() {
    use burn::module::list_param_ids;
    let (cfg, device) = (tiny(), cpu());
    let ids = |g: Vec<burn::module::ParamId>| g.into_iter().map(|id| id.val()).collect::<Vec<_>>();
    let generator = ids(list_param_ids(&Generator::new(&cfg, &device)));
    assert_eq!(generator, ids(list_param_ids(&Generator::new(&cfg, &device))));
    let autoencoder = ids(list_param_ids(&Autoencoder::new(&cfg, &device)));
    // An optimiser tells parameters apart by id: within a model and across the two (the
    // generator's decoder can start from the autoencoder's, ids included).
    let mut all: Vec<u64> = generator.iter().chain(&autoencoder).copied().collect();
    let n = all.len();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), n, "{n} parameters");
    assert!(generator.len() > 20 && autoencoder.len() > 10);
}

#[test]
fn checkpoints_round_trip_and_bad_weights_are_diagnosed() {
    let cfg = tiny();
    let device = cpu();
    device.seed(3);
    let g = Generator::new(&cfg, &device);
    let dir = tempdir("roundtrip");
    let bpk = dir.join("generator.bpk");
    g.clone().save_file(&bpk).unwrap();
    std::fs::write(dir.join("generator.ron"), cfg.to_ron()).unwrap();
    device.seed(4);
    let fresh = Generator::new(&cfg, &device);
    assert_ne!(params(&fresh), params(&g), "two seeds must differ for this test to mean anything");
    let loaded = load_weights(Generator::new(&cfg, &device), &bpk).unwrap();
    assert_eq!(params(&loaded), params(&g));
    let st = dir.join("generator.safetensors");
    save_safetensors(&g, &st).unwrap();
    let loaded = load_weights(Generator::new(&cfg, &device), &st).unwrap();
    assert_eq!(params(&loaded), params(&g));
    // The same weights are the same bytes, in either format: parameter ids come from the
    // model's structure, and the safetensors metadata has one entry (a hash map's order varies).
    device.seed(3);
    let again = dir.join("again.bpk");
    Generator::new(&cfg, &device).save_file(&again).unwrap();
    assert!(std::fs::read(&again).unwrap() == std::fs::read(&bpk).unwrap(), "a second .bpk of the same weights");
    for i in 0..3 {
        let st_again = dir.join(format!("again{i}.safetensors"));
        save_safetensors(&g, &st_again).unwrap();
        assert!(std::fs::read(&st_again).unwrap() == std::fs::read(&st).unwrap(), "safetensors {i}");
    }
    // Through the backend: the `.ron` beside the weights is found.
    let backend = Grounded::load(&bpk, None).unwrap();
    assert!(rocc::backend::OccupancyBackend::name(&backend).starts_with("grounded-tiny-"));
    // Diagnostics.
    let code = |r: Result<Grounded, rocc::diag::Diagnostic>| r.err().map(|d| d.code.to_string());
    assert_eq!(code(Grounded::load(&dir.join("nope.bpk"), None)), Some("E0901".into()));
    std::fs::write(dir.join("w.pt"), b"x").unwrap();
    std::fs::write(dir.join("w.ron"), cfg.to_ron()).unwrap();
    assert_eq!(code(Grounded::load(&dir.join("w.pt"), None)), Some("E0904".into()));
    std::fs::copy(&st, dir.join("orphan.safetensors")).unwrap();
    assert_eq!(code(Grounded::load(&dir.join("orphan.safetensors"), None)), Some("E0902".into()));
    let mut other = cfg.clone();
    other.decoder.width = 32;
    std::fs::write(dir.join("other.ron"), other.to_ron()).unwrap();
    assert_eq!(code(Grounded::load(&bpk, Some(&dir.join("other.ron")))), Some("E0903".into()));
    assert_eq!(code(Grounded::load(&st, Some(&dir.join("other.ron")))), Some("E0903".into()));
    let ae = dir.join("autoencoder.bpk");
    Autoencoder::new(&cfg, &device).save_file(&ae).unwrap();
    assert_eq!(code(Grounded::load(&ae, Some(&dir.join("generator.ron")))), Some("E0903".into()));
    std::fs::write(dir.join("bad.ron"), "(name: \"x\")").unwrap();
    assert_eq!(code(Grounded::load(&bpk, Some(&dir.join("bad.ron")))), Some("E0902".into()));
}

#[test]
fn rocc_edit_reruns_the_learned_backend_of_a_grounded_clip() {
    use rocc::compile::{OccBackend, Options, Stage, batch};
    use rocc::edit::{ClipEdit, Edit, edit_clip, read_boxes_json};
    let cfg = tiny();
    let device = cpu();
    device.seed(11);
    let dir = tempdir("edit");
    let bpk = dir.join("generator.bpk");
    Generator::new(&cfg, &device).save_file(&bpk).unwrap();
    std::fs::write(dir.join("generator.ron"), cfg.to_ron()).unwrap();
    let g = std::sync::Arc::new(Grounded::load(&bpk, None).unwrap());
    let scn = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
    let out = dir.join("out");
    let o = Options {
        stage: Stage::Occ,
        frames: Some("0".into()),
        previews: false,
        backend: OccBackend::Grounded(g.clone()),
        ..Options::default()
    };
    assert!(batch::run(std::slice::from_ref(&scn), &out, &o, true).failures.is_empty());
    let clip = out.join("replayed_cut_in/ego");
    let manifest = || -> rocc::output::Manifest {
        serde_json::from_str(&std::fs::read_to_string(clip.join("manifest.json")).unwrap()).unwrap()
    };
    let m = manifest();
    assert!(m.backend.starts_with("grounded-tiny-"), "{}", m.backend);
    assert_eq!(m.weights.as_deref(), Some(bpk.to_str().unwrap()));
    assert_eq!(m.grounded_config.as_deref(), Some(dir.join("generator.ron").to_str().unwrap()));
    let occ = || rocc::eval::occ::read_occ(&clip.join("occ/000000.npy")).unwrap();
    let before = occ();

    // The edit reruns the same model on the edited boxes and the re-rasterised BEV.
    let ce = ClipEdit { scenario: Some(scn.clone()), ..Default::default() };
    let ins = Edit::Insert { kind: "sedan".into(), x: 20.0, y: 0.0, yaw: 0.0 };
    edit_clip(&clip, std::slice::from_ref(&ins), &ce).expect("a grounded clip is editable");
    let boxes = &read_boxes_json(&clip.join("boxes.json")).unwrap()[0].boxes;
    assert!(boxes.iter().any(|b| b.agent == "inserted_sedan_1"));
    let bev = rocc::output::read_npz(&rocc::output::bev_frame_path(&clip, 0)).unwrap();
    let gboxes: Vec<GBox> = boxes.iter().map(GBox::from_ego).collect();
    let after = occ();
    assert_eq!(after, g.predict(&gboxes, &bev.masks, &bev.aux), "not the grounded model's output");
    assert_ne!(after, before, "the inserted car changed nothing");
    let m2 = manifest();
    assert_eq!((m2.backend.as_str(), m2.weights.as_deref()), (m.backend.as_str(), m.weights.as_deref()));
    assert_eq!(m2.edits.len(), 1);

    // Weights gone: a coded error naming the path; nothing written.
    let moved = dir.join("moved");
    std::fs::create_dir_all(&moved).unwrap();
    std::fs::rename(&bpk, moved.join("g.bpk")).unwrap();
    let written = std::fs::read(clip.join("manifest.json")).unwrap();
    let del = Edit::Delete { agent: "inserted_sedan_1".into() };
    let e = edit_clip(&clip, std::slice::from_ref(&del), &ce).unwrap_err();
    assert_eq!(e[0].code, "E0901");
    assert!(e[0].message.contains(bpk.to_str().unwrap()), "{}", e[0].message);
    assert_eq!(std::fs::read(clip.join("manifest.json")).unwrap(), written);
    // Other weights (another seed) are refused: they would mix two models in one clip.
    std::fs::write(moved.join("g.ron"), cfg.to_ron()).unwrap();
    device.seed(12);
    Generator::new(&cfg, &device).save_file(moved.join("other.bpk")).unwrap();
    std::fs::write(moved.join("other.ron"), cfg.to_ron()).unwrap();
    let other = ClipEdit { weights: Some(moved.join("other.bpk")), ..ce.clone() };
    assert_eq!(edit_clip(&clip, std::slice::from_ref(&del), &other).unwrap_err()[0].code, "E0712");
    // The same weights elsewhere, given with `--weights`: accepted, and the manifest follows them.
    let same = ClipEdit { weights: Some(moved.join("g.bpk")), ..ce.clone() };
    edit_clip(&clip, &[del], &same).unwrap();
    assert_eq!(occ(), before, "deleting the insertion restores the model's output");
    assert_eq!(manifest().weights.as_deref(), Some(moved.join("g.bpk").to_str().unwrap()));
}

#[test]
fn bundled_configs_are_valid() {
    let paper = GroundedConfig::from_ron(include_str!("../configs/paper.ron")).unwrap();
    assert_eq!((paper.latents, paper.latent_dim, paper.max_foreground), (4096, 128, 512));
    assert_eq!((paper.decoder.width, paper.decoder.blocks, paper.decoder.heads), (384, 6, 6));
    assert_eq!(paper.max_gaussians(), 96);
    assert_eq!((paper.gaussians.offset_bound, paper.gaussians.min_scale), (7.0, 0.25));
    let small = GroundedConfig::from_ron(include_str!("../configs/cpu-small.ron")).unwrap();
    assert_eq!(GroundedConfig::from_ron(&small.to_ron()).unwrap(), small);
    let mut bad = small.clone();
    bad.decoder.heads = 5;
    bad.max_foreground = 10_000;
    let e = bad.validate().unwrap_err();
    assert!(e.contains("multiple of `heads`") && e.contains("max_foreground"), "{e}");
}

/// A directory for this test's outputs, removed when dropped.
fn tempdir(name: &str) -> tmp::TempDir {
    tmp::TempDir::new("rocc-grounded", name)
}
