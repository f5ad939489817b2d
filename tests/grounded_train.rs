//! The grounded model learns: a small configuration trained on the CPU for a bounded number of
//! steps on a corpus rocc compiles itself beats the trivial baseline (every column gets the
//! training set's per-height-layer majority label) on a held-out scene under the shared scorer;
//! training resumes from its checkpoint; and `rocc compile --backend grounded` writes occupancy
//! and LiDAR in the procedural backend's layout.

use rocc::backend::grounded::{GroundedConfig, cpu};
use rocc::compile::{OccBackend, Options, Stage, batch};
use rocc::learn::{Stage as TrainStage, TrainOptions, train};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};

/// burn's CPU random generator is one per process, and every training run seeds it before
/// drawing its initial weights: two runs at once (tests run on parallel threads) would draw
/// from one stream. The tests here train one at a time.
fn one_run_at_a_time() -> MutexGuard<'static, ()> {
    static RUNS: Mutex<()> = Mutex::new(());
    RUNS.lock().unwrap_or_else(|e| e.into_inner())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn compile(files: &[&str], out: &Path, frames: &str, backend: OccBackend, stage: Stage) {
    let inputs: Vec<PathBuf> = files.iter().map(|f| root().join("scenarios").join(f)).collect();
    let opts = Options { stage, frames: Some(frames.into()), previews: false, backend, ..Options::default() };
    let r = batch::run(&inputs, out, &opts, true);
    assert!(r.failures.is_empty(), "{:?}", r.failures.iter().map(|f| &f.input).collect::<Vec<_>>());
}

#[test]
fn a_small_model_trained_on_the_cpu_beats_the_layer_majority_baseline() {
    let _serial = one_run_at_a_time();
    let dir = std::env::temp_dir().join(format!("rocc-grounded-train-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (data, val, out) = (dir.join("train"), dir.join("val"), dir.join("model"));
    compile(
        &["ambulance_crowded_intersection.scn", "highway_merge.scn", "pedestrian_midblock.scn", "ciren_sideswipe.scn"],
        &data,
        "0,12,24,36",
        OccBackend::Procedural,
        Stage::Occ,
    );
    compile(&["rear_end_queue.scn"], &val, "0,20", OccBackend::Procedural, Stage::Occ);

    let mut config = GroundedConfig::from_ron(include_str!("../configs/cpu-small.ron")).unwrap();
    config.train.val_max_frames = 2;
    config.train.checkpoint_every = 10;
    let mut opts = TrainOptions {
        stage: TrainStage::Generator,
        data: data.clone(),
        val: Some(val.clone()),
        config: config.clone(),
        out: out.clone(),
        resume: false,
        init: None,
        device: cpu(),
        quiet: true,
        max_steps: Some(30),
        epochs: Some(100),
        precision: Default::default(),
    };
    let report = train(&opts).unwrap();
    assert_eq!(report.steps, 30);
    let base = report.baseline.clone().expect("a validation set was given");
    let got = report.epochs.last().and_then(|e| e.val.clone()).expect("validation after the run");
    let iou =
        |s: &rocc::eval::occ::OccScores, name: &str| s.classes.iter().find(|c| c.name == name).map(|c| c.iou).unwrap();
    let line = format!(
        "baseline fg-mIoU {:.2} mIoU_US {:.2} occ-IoU {:.2} vehicle {:.2}; model fg-mIoU {:.2} mIoU_US {:.2} occ-IoU {:.2} vehicle {:.2}",
        base.fg_miou,
        base.miou_us,
        base.occ_iou,
        iou(&base, "vehicle"),
        got.fg_miou,
        got.miou_us,
        got.occ_iou,
        iou(&got, "vehicle")
    );
    eprintln!("{line}");
    // The baseline never predicts an agent, so its vehicle IoU is 0; the model must find the
    // held-out scene's vehicles from their boxes without losing free space or background.
    assert_eq!(iou(&base, "vehicle"), 0.0, "{line}");
    assert!(iou(&got, "vehicle") > 5.0, "{line}");
    assert!(got.fg_miou > base.fg_miou + 0.5, "{line}");
    assert!(got.miou_us > base.miou_us, "{line}");
    assert!(got.occ_iou > base.occ_iou - 1.0, "{line}");

    // Resume continues from the last checkpoint (step 30), not from scratch.
    opts.resume = true;
    opts.max_steps = Some(32);
    let resumed = train(&opts).unwrap();
    assert_eq!(resumed.steps, 32);

    // The trained weights drive `rocc compile`: same layout as the procedural backend.
    let weights = out.join("generator.bpk");
    assert!(weights.is_file() && out.join("generator.ron").is_file());
    let g = Arc::new(rocc::backend::grounded::Grounded::load(&weights, None).unwrap());
    let compiled = dir.join("compiled");
    compile(&["rear_end_queue.scn"], &compiled, "0,1", OccBackend::Grounded(g.clone()), Stage::Lidar);
    // Deterministic on any thread count, like the procedural backend.
    let one = dir.join("one-thread");
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| compile(&["rear_end_queue.scn"], &one, "0,1", OccBackend::Grounded(g.clone()), Stage::Occ));
    for f in ["occ/000000.npy", "occ/000001.npy"] {
        let (a, b) = (compiled.join("rear_end_queue/ego").join(f), one.join("rear_end_queue/ego").join(f));
        assert!(std::fs::read(a).unwrap() == std::fs::read(b).unwrap(), "{f} differs between 1 and N threads");
    }
    let clip = compiled.join("rear_end_queue/ego");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(clip.join("manifest.json")).unwrap()).unwrap();
    assert!(manifest["backend"].as_str().unwrap().starts_with("grounded-cpu-small-"), "{manifest}");
    for f in ["bev/000000.npz", "occ/000000.npy", "lidar/000000.bin", "lidar/000000.pcd", "boxes.json"] {
        assert!(clip.join(f).is_file(), "{f}");
    }
    let occ = rocc::backend::read_npy(&clip.join("occ/000000.npy")).unwrap();
    let c = occ.counts();
    assert!(c[2] > 0, "vehicles in the learned occupancy: {c:?}");
    assert!(std::fs::metadata(clip.join("lidar/000000.bin")).unwrap().len() > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A small corpus (four frames of one scene) and a `cpu-small` config on `crop`-column crops with
/// nothing held out, in a fresh directory.
fn small_run(name: &str, crop: usize) -> (PathBuf, PathBuf, GroundedConfig) {
    let dir = std::env::temp_dir().join(format!("rocc-grounded-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let data = dir.join("data");
    compile(&["pedestrian_midblock.scn"], &data, "0,10,20,30", OccBackend::Procedural, Stage::Occ);
    let mut config = GroundedConfig::from_ron(include_str!("../configs/cpu-small.ron")).unwrap();
    config.train.crop = crop;
    config.train.val_fraction = 0.0;
    (dir, data, config)
}

/// Options for `steps` generator steps from scratch on the CPU.
fn small_opts(
    data: &Path,
    config: &GroundedConfig,
    out: PathBuf,
    steps: usize,
    precision: rocc::backend::grounded::attention::Precision,
) -> TrainOptions {
    TrainOptions {
        stage: TrainStage::Generator,
        data: data.to_path_buf(),
        val: None,
        config: config.clone(),
        out,
        resume: false,
        init: None,
        device: cpu(),
        quiet: true,
        max_steps: Some(steps),
        epochs: Some(100),
        precision,
    }
}

/// Mixed precision through the training loop (the CPU computes f16 too, slowly): steps train,
/// and a gradient scale far beyond half precision's range makes every step overflow, so each is
/// skipped and the weights stay as they started.
#[test]
fn mixed_precision_trains_and_skips_steps_whose_gradient_overflows() {
    let _serial = one_run_at_a_time();
    use rocc::backend::grounded::attention::{GradScale, Precision};
    use rocc::backend::grounded::{Generator, load_weights};
    let (dir, data, config) = small_run("mixed", 64);
    let opts =
        |out: &str, steps: usize, precision: Precision| small_opts(&data, &config, dir.join(out), steps, precision);
    let mixed = train(&opts("mixed", 2, Precision::Mixed(GradScale::default()))).unwrap();
    assert_eq!((mixed.precision, mixed.steps, mixed.skipped_steps), ("mixed", 2, 0));

    let scale = GradScale::starting_at(50);
    let over = train(&opts("overflow", 2, Precision::Mixed(scale.clone()))).unwrap();
    assert_eq!((over.steps, over.skipped_steps), (2, 2));
    assert_eq!(scale.value(), (1u64 << 48) as f32);
    let start = train(&opts("start", 0, Precision::Full)).unwrap();
    let weights = |p: &Path| {
        let g = load_weights(Generator::new(&config, &cpu()), p).unwrap();
        g.decoder.transformer.layers[0].mha.key.weight.val().into_data().try_to_vec::<f32>().unwrap()
    };
    assert_eq!(weights(&over.weights), weights(&start.weights));
    assert_ne!(weights(&mixed.weights), weights(&start.weights));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Training is deterministic on any thread count: burn's CPU operations (on all cores through
/// rayon) and rocc's own split their work without changing any sum's order.
#[test]
fn training_gives_the_same_weights_on_any_thread_count() {
    let _serial = one_run_at_a_time();
    use rocc::backend::grounded::{Generator, load_weights};
    let (dir, data, config) = small_run("threads", 96);
    let run = |threads: usize| {
        let opts = small_opts(&data, &config, dir.join(format!("t{threads}")), 2, Default::default());
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let report = pool.install(|| train(&opts)).unwrap();
        let file = std::fs::read(&report.weights).unwrap();
        let g = load_weights(Generator::new(&config, &cpu()), &report.weights).unwrap();
        // Parameters of every part, in a fixed order.
        let mut all = Vec::new();
        for t in [
            g.decoder.input.weight.val(),
            g.decoder.head.weight.val(),
            g.decoder.transformer.layers[0].pwff.linear_inner.weight.val(),
            g.decoder.layer_bias.val(),
        ] {
            all.extend(t.into_data().try_to_vec::<f32>().unwrap());
        }
        for c in &g.bev.convs {
            all.extend(c.weight.val().into_data().try_to_vec::<f32>().unwrap());
        }
        (all, file)
    };
    let one = run(1);
    for threads in [3, 2] {
        let (params, file) = run(threads);
        assert_eq!(one.0, params, "{threads} threads");
        // The weights file too, byte for byte (parameter ids included).
        assert!(one.1 == file, "{threads} threads: the .bpk bytes");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
