//! Inference of the learned backend: frames batched per forward pass give the labels of single
//! frames, byte for byte, through the library and through `rocc compile`; device selection and
//! GPU failures are diagnostics (E0908, E0910-E0913), never a panic; mixed precision is refused
//! where it cannot run (E0914).

#[path = "support/grounded_tiny.rs"]
mod grounded_tiny;

use ndarray::Array3;
use rocc::backend::grounded::config::GroundedConfig;
use rocc::backend::grounded::guard::{classify, guarded};
use rocc::backend::grounded::model::bev_batch;
use rocc::backend::grounded::splat::Region;
use rocc::backend::grounded::{DeviceKind, FrameIn, GBox, Generator, Grounded, HostBatch, cpu, latents};
use rocc::backend::layout::{PEDESTRIAN, VEHICLE};
use rocc::raster::layout::{CH_DRIVABLE, GRID, N_AUX, N_MASKS};
use std::path::{Path, PathBuf};
use std::process::Command;

fn tempdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rocc-grounded-infer-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn bev(road: std::ops::Range<usize>) -> (Array3<i8>, Array3<i32>) {
    let mut masks = Array3::<i8>::zeros((N_MASKS, GRID, GRID));
    masks.slice_mut(ndarray::s![CH_DRIVABLE, .., road]).fill(1);
    let mut aux = Array3::<i32>::zeros((N_AUX, GRID, GRID));
    aux.slice_mut(ndarray::s![3, 150..170, 190..200]).fill(4);
    (masks, aux)
}

fn gbox(label: u8, x: f64, y: f64, l: f64, yaw: f64) -> GBox {
    GBox { label, x, y, z: 0.8, l, w: 1.9, h: 1.6, yaw }
}

type FrameBoxes<'a> = (Vec<GBox>, &'a Array3<i8>, &'a Array3<i32>);

/// The host batch and BEV of `frames` for the model's forward pass.
fn model_input(cfg: &GroundedConfig, frames: &[FrameBoxes]) -> (HostBatch, Vec<f32>) {
    let hb = HostBatch::new(frames.iter().map(|(b, m, _)| latents::build(cfg, b, m)).collect());
    (hb, bev_batch(&frames.iter().map(|(_, m, a)| (*m, *a)).collect::<Vec<_>>()))
}

/// A background head that speaks (its output layer is zero-initialised), loud enough to move
/// voxels between free and background.
fn loud_background(model: &mut Generator, cfg: &GroundedConfig) {
    let (f, nz) = (cfg.bev_features(), rocc::backend::layout::NZ);
    let loud = burn::module::Initializer::Uniform { min: -20.0, max: 20.0 };
    model.bg_out = Some(burn::nn::conv::Conv2dConfig::new([f, nz], [1, 1]).with_initializer(loud).init(&cpu()));
}

#[test]
fn a_batch_of_three_frames_gives_the_labels_of_three_single_frames() {
    let cfg = grounded_tiny::tiny();
    let device = cpu();
    device.seed(21);
    let model = Generator::new(&cfg, &device);
    // Three frames of different latent counts (0, 1 and 3 boxes; two road layouts), so their
    // sets are padded differently in the batch.
    let (m0, a0) = bev(180..220);
    let (m1, a1) = bev(100..300);
    let frames = [
        FrameIn { boxes: vec![], masks: &m0, aux: &a0 },
        FrameIn { boxes: vec![gbox(VEHICLE, 5.0, 0.5, 4.5, 0.3)], masks: &m1, aux: &a1 },
        FrameIn {
            boxes: vec![
                gbox(VEHICLE, -8.0, 1.0, 9.0, 0.0),
                gbox(PEDESTRIAN, 3.0, 6.0, 0.6, 1.2),
                gbox(VEHICLE, 20.0, -2.0, 4.2, 3.0),
            ],
            masks: &m0,
            aux: &a0,
        },
    ];
    let single = Grounded::from_model(cfg.clone(), model.clone(), "t");
    let alone: Vec<Array3<u8>> = frames.iter().map(|f| single.predict(&f.boxes, f.masks, f.aux)).collect();
    let batched = Grounded::from_model(cfg, model, "t").on(DeviceKind::Cpu, 3).unwrap();
    let together = batched.predict_frames(&frames).unwrap();
    assert_eq!(together.len(), 3);
    for (i, (a, b)) in alone.iter().zip(&together).enumerate() {
        assert!(a == b, "frame {i}: batched labels differ from the frame alone");
    }
    assert_ne!(alone[0], alone[2], "the boxes changed nothing: the test would prove nothing");
}

/// The CPU's labels come from `head` on the host: they must be the argmax of the tensor path's
/// logits, bit for bit, including the background head's gated residual (here not zero).
#[test]
fn host_labels_are_the_argmax_of_the_logits() {
    let cfg = grounded_tiny::tiny();
    let device = cpu();
    device.seed(8);
    let mut model = Generator::new(&cfg, &device);
    let (m0, a0) = bev(150..250);
    let (m1, a1) = bev(100..300);
    let frames = [
        (vec![gbox(VEHICLE, 5.0, 0.5, 4.5, 0.3), gbox(PEDESTRIAN, 3.0, 6.0, 0.6, 1.2)], &m0, &a0),
        (vec![gbox(VEHICLE, -8.0, 1.0, 9.0, 0.0)], &m1, &a1),
    ];
    let (hb, bev) = model_input(&cfg, &frames);
    let region = Region { i0: 150, j0: 170, ni: 60, nj: 50 };
    let argmax = |m: &Generator| -> Vec<u8> {
        let logits = m.forward(bev.clone(), &hb, region).logits;
        logits.argmax(1).to_data().iter::<i64>().map(|l| l as u8).collect()
    };
    let differ = |a: &[u8], b: &[u8]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    let without = model.labels(bev.clone(), &hb, region);
    assert_eq!(without.len(), 2 * region.voxels());
    assert_eq!(differ(&without, &argmax(&model)), 0, "labels differ from the logits' argmax");
    loud_background(&mut model, &cfg);
    let with = model.labels(bev.clone(), &hb, region);
    assert_eq!(differ(&with, &argmax(&model)), 0, "labels differ from the logits' argmax");
    let moved = differ(&with, &without);
    assert!(moved > 1000, "the residual moved {moved} labels: the test would prove little");
}

/// A device that binds less than a frame's logits (Mesa's software Vulkan: 128 MiB; a frame's are
/// 184 MB) labels the grid a strip of rows at a time, from one decoder pass: the labels are
/// those of the whole grid's argmax, for the generator (background head speaking) and the
/// autoencoder.
#[test]
fn labels_in_strips_are_the_labels_of_the_whole_grid() {
    use rocc::backend::grounded::model::Autoencoder;
    use rocc::backend::grounded::strips::{labels, rows_per_strip};
    let cfg = grounded_tiny::tiny();
    let device = cpu();
    device.seed(12);
    let mut model = Generator::new(&cfg, &device);
    loud_background(&mut model, &cfg);
    let (m0, a0) = bev(150..250);
    let (m1, a1) = bev(100..300);
    let frames = [
        (vec![gbox(VEHICLE, 5.0, 0.5, 4.5, 0.3), gbox(PEDESTRIAN, -30.0, 6.0, 0.6, 1.2)], &m0, &a0),
        (vec![gbox(VEHICLE, -8.0, 40.0, 9.0, 0.0), gbox(VEHICLE, 44.0, -3.0, 4.0, 1.0)], &m1, &a1),
    ];
    let (hb, bev) = model_input(&cfg, &frames);
    let whole = model.labels(bev.clone(), &hb, Region::full());
    // A row of 2 frames' logits is 0.9 MB: a 5 MiB buffer takes 5 rows a strip. 7 and 160 rows
    // leave an uneven last strip.
    let rows = rows_per_strip(2, Some(5 << 20));
    assert_eq!(rows, 5);
    let prep = model.prepare(bev.clone(), &hb, Region::full());
    for rows in [rows, 7, 160] {
        let strips = labels(2, rows, |r| model.region_out(&prep, &hb, r).logits);
        let differ = strips.iter().zip(&whole).filter(|(a, b)| a != b).count();
        assert_eq!((strips.len(), differ), (whole.len(), 0), "{rows} rows a strip");
    }
    let classes = |v: &[u8]| (0..9u8).filter(|c| v.contains(c)).count();
    assert!(classes(&whole) >= 3, "the scene's labels would prove little");

    let ae = Autoencoder::new(&cfg, &device);
    // The autoencoder reads the generator's labels as its ground truth.
    let truth = rocc::backend::grounded::Grounded::from_model(cfg.clone(), model, "t").predict(&frames[0].0, &m0, &a0);
    let hb1 = HostBatch::new(vec![latents::build(&cfg, &frames[0].0, &m0)]);
    let enc = Autoencoder::encoder_input(&cfg, &hb1, &[&truth]);
    let logits = ae.forward(enc.clone(), &hb1, Region::full(), None).logits;
    let argmax: Vec<u8> = logits.argmax(1).to_data().iter::<i64>().map(|l| l as u8).collect();
    assert_eq!(ae.labels_in_strips(enc, &hb1, 33), argmax, "the autoencoder's strips differ");
}

/// Weights of the tiny model in `dir` (`generator.bpk` with its `.ron`).
fn weights(dir: &Path) -> PathBuf {
    let cfg = grounded_tiny::tiny();
    let device = cpu();
    device.seed(5);
    let bpk = dir.join("generator.bpk");
    burn::module::Module::save_file(Generator::new(&cfg, &device), &bpk).unwrap();
    std::fs::write(dir.join("generator.ron"), cfg.to_ron()).unwrap();
    bpk
}

fn rocc(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rocc")).args(args).output().unwrap()
}

fn files_under(dir: &Path, sub: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir.join(sub))
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| (p.file_name().unwrap().into(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    v
}

#[test]
fn rocc_compile_writes_the_same_occupancy_and_lidar_for_any_grounded_batch() {
    let dir = tempdir("compile");
    let bpk = weights(&dir);
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
    let run = |out: &str, batch: &str| {
        let o = rocc(&[
            "compile",
            scn.to_str().unwrap(),
            "-o",
            dir.join(out).to_str().unwrap(),
            "--frames",
            "0,3,6,9,12",
            "--no-previews",
            "-q",
            "--backend",
            "grounded",
            "--weights",
            bpk.to_str().unwrap(),
            "--device",
            "cpu",
            "--grounded-batch",
            batch,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        dir.join(out).join("replayed_cut_in/ego")
    };
    let (one, three) = (run("one", "1"), run("three", "3"));
    for (sub, n) in [("occ", 5), ("lidar", 10)] {
        let (a, b) = (files_under(&one, sub), files_under(&three, sub));
        assert_eq!(a.len(), n, "{sub}");
        assert!(a == b, "{sub}/ differs between --grounded-batch 1 and 3");
    }
    let manifest = std::fs::read_to_string(three.join("manifest.json")).unwrap();
    assert!(manifest.contains("\"device\": \"cpu\""), "{manifest}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn device_options_are_checked() {
    let dir = tempdir("options");
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
    let out = dir.join("out");
    let base = ["compile", scn.to_str().unwrap(), "-o", out.to_str().unwrap(), "--frames", "0", "-q"];
    // The procedural backend takes neither option.
    let o = rocc(&[&base[..], &["--device", "cpu"]].concat());
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("E0908"));
    let o = rocc(&[&base[..], &["--grounded-batch", "2"]].concat());
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("E0908"));
    let o = rocc(&[&base[..], &["--precision", "mixed"]].concat());
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("E0908"));
    let o = rocc(&[&base[..], &["--device", "tpu"]].concat());
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("expected cpu, wgpu or cuda"));
    assert!(!out.exists(), "nothing is written on a bad option");
    assert_eq!("WGPU".parse::<DeviceKind>(), Ok(DeviceKind::Wgpu));
    // A build without a GPU feature says which rebuild gives it.
    for (kind, feature) in [(DeviceKind::Wgpu, cfg!(feature = "wgpu")), (DeviceKind::Cuda, cfg!(feature = "cuda"))] {
        if !feature {
            let e = kind.open().unwrap_err();
            assert_eq!(e.code, "E0908");
            assert!(e.help.unwrap_or_default().contains(&format!("--features {kind}")));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gpu_failure_messages_are_classified() {
    let code = |m: &str| classify(m).code;
    // cubecl's own words (cubecl-runtime's IoError, cubecl-wgpu's setup).
    assert_eq!(code("can't allocate buffer of size: 3499028096\nbacktrace ..."), "E0912");
    assert_eq!(code("Buffer size 3499028096 exceeds the max_buffer_size limit 268435456"), "E0912");
    assert_eq!(code("out of device memory allocating 8589934592 bytes"), "E0911");
    assert_eq!(code("CUDA_ERROR_OUT_OF_MEMORY: out of memory"), "E0911");
    assert_eq!(code("Unable to acquire wgpu device: NoAdapter"), "E0910");
    assert_eq!(code("No possible adapter available for backend"), "E0910");
    assert_eq!(code("CUDA_ERROR_NO_DEVICE: no CUDA-capable device is detected"), "E0910");
    assert_eq!(code("index out of bounds: the len is 3 but the index is 7"), "E0913");
    let d = classify("can't allocate buffer of size: 3499028096\n   0: std::backtrace ...");
    assert!(d.message.contains("3499028096") && !d.message.contains("backtrace"), "{}", d.message);
    assert!(d.help.unwrap_or_default().contains("--grounded-batch"));
}

#[test]
fn a_panic_inside_device_work_is_a_diagnostic() {
    assert_eq!(guarded(|| 7).unwrap(), 7);
    let e = guarded(|| -> u32 { panic!("can't allocate buffer of size: 3499028096") }).unwrap_err();
    assert_eq!(e.code, "E0912");
    // The device's own thread fails and the caller only learns that it did: the device thread's
    // message (recorded by the hook) still decides the code.
    let e = guarded(|| {
        let t = std::thread::Builder::new().name("DS-test-0".into());
        let h = t.spawn(|| panic!("out of device memory allocating 8589934592 bytes")).unwrap();
        if h.join().is_err() {
            panic!("the device thread stopped");
        }
    })
    .unwrap_err();
    assert_eq!(e.code, "E0911", "{}", e.message);
    // Outside a guard, panics are ordinary panics again.
    assert!(std::panic::catch_unwind(|| panic!("plain")).is_err());
}

/// Mixed precision is for GPUs: `rocc compile` and `rocc train` refuse it on the CPU before any
/// work, with E0914 and the way back.
#[test]
fn mixed_precision_is_refused_on_the_cpu() {
    let dir = tempdir("mixed");
    let bpk = weights(&dir);
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
    let out = dir.join("out");
    let o = rocc(&[
        "compile",
        scn.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--frames",
        "0",
        "-q",
        "--backend",
        "grounded",
        "--weights",
        bpk.to_str().unwrap(),
        "--precision",
        "mixed",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("E0914") && err.contains("--precision full"), "{err}");
    assert!(!out.join("replayed_cut_in").exists(), "nothing is compiled");
    let cfg = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/cpu-small.ron");
    let o = rocc(&[
        "train",
        "generator",
        "--data",
        dir.to_str().unwrap(),
        "--config",
        cfg.to_str().unwrap(),
        "-o",
        dir.join("model").to_str().unwrap(),
        "--precision",
        "mixed",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("E0914"), "{err}");
    let o = rocc(&["train", "generator", "--data", ".", "--config", "x", "-o", "y", "--precision", "half"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected full or mixed"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_device_codes_are_explained() {
    for code in ["E0910", "E0911", "E0912", "E0913", "E0914"] {
        let o = rocc(&["explain", code]);
        assert!(o.status.success(), "{code}");
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(text.contains("--device") || text.contains("device"), "{code}: {text}");
    }
}
