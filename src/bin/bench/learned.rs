//! `bench train` and `bench grounded`: the learned backend's training seconds per step and
//! inference time per frame, on the CPU or a GPU.

use super::*;
use rocc::backend::grounded::{DeviceKind, GroundedConfig, load_config};

/// `configs/NAME.ron` of the repository.
fn config(name: &str) -> Result<GroundedConfig, String> {
    load_config(&root().join(format!("configs/{name}.ron"))).map_err(|d| d.message)
}

/// The `--precision full|mixed` of a bench command.
fn precision(args: &[String]) -> Result<rocc::backend::grounded::attention::Precision, String> {
    opt(args, "--precision").unwrap_or("full").parse()
}

/// `bench train [paper] [--device cpu|wgpu|cuda] [--precision full|mixed] [--steps N]`: training
/// seconds per step of the generator on a corpus compiled here (12 frames of the crowded
/// junction), `cpu-small`, and `paper` when asked.
pub fn bench_train(args: &[String]) {
    let kind: DeviceKind = match opt(args, "--device").unwrap_or("cpu").parse() {
        Ok(k) => k,
        Err(e) => return println!("  {e}"),
    };
    let device = match kind.open() {
        Ok(d) => d,
        Err(e) => return println!("  {e}"),
    };
    let precision = match precision(args) {
        Ok(p) => p,
        Err(e) => return println!("  {e}"),
    };
    // A GPU compiles kernels for new tensor sizes over its first tens of steps: its steady state
    // needs `--steps 30` or more.
    let steps: usize = opt(args, "--steps").and_then(|s| s.parse().ok()).unwrap_or(6).max(2);
    if let Err(d) = rocc::backend::grounded::attention::check(&precision, &device) {
        return println!("  {} {}", d.code, d.message);
    }
    println!(
        "== train: generator seconds per step on {kind}, {} precision (a corpus of 12 frames compiled here)",
        precision.name()
    );
    let dir = std::env::temp_dir().join(format!("rocc-bench-train-{}", std::process::id()));
    let Some(corpus) = corpus(&dir) else {
        return println!("  the corpus did not compile");
    };
    let mut names = vec!["cpu-small"];
    if args.iter().any(|a| a == "paper") {
        names.push("paper");
    }
    for name in names {
        let config = match config(name) {
            Ok(c) => c,
            Err(e) => {
                println!("  {name}: {e}");
                continue;
            }
        };
        let topts = rocc::learn::TrainOptions {
            stage: rocc::learn::Stage::Generator,
            data: corpus.clone(),
            val: None,
            config: GroundedConfig {
                train: rocc::backend::grounded::config::TrainConfig { val_fraction: 0.0, ..config.train.clone() },
                ..config.clone()
            },
            out: dir.join(name),
            resume: false,
            init: None,
            device: device.clone(),
            quiet: true,
            max_steps: Some(steps),
            epochs: Some(100),
            precision: precision.clone(),
        };
        let cpu0 = cpu_secs().unwrap_or(f64::NAN);
        match rocc::learn::train(&topts) {
            Ok(rep) => println!(
                "  {name:<10} batch {} crop {}: {}; {:.3} CPU s per step (the whole run over its steps)",
                config.train.batch,
                config.train.crop,
                rocc::learn::step_summary(&rep.step_phases).unwrap_or_default(),
                (cpu_secs().unwrap_or(f64::NAN) - cpu0) / rep.step_phases.len().max(1) as f64
            ),
            Err(e) => println!("  {name}: {e}"),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// 12 frames of the crowded junction compiled to procedural occupancy under `dir`: the
/// training benches' corpus.
fn corpus(dir: &Path) -> Option<PathBuf> {
    use rocc::compile::{OccBackend, Stage};
    let corpus = dir.join("corpus");
    let opts = Options {
        stage: Stage::Occ,
        frames: Some("0..12".into()),
        previews: false,
        backend: OccBackend::Procedural,
        ..Options::default()
    };
    let r = batch::run(&[root().join("scenarios/ambulance_crowded_intersection.scn")], &corpus, &opts, true);
    r.failures.is_empty().then_some(corpus)
}

/// `bench loss [--claimed F,G]`: the host side of a GPU training step's loss at `paper` scale
/// (batch 6, full grids: 30.7 M voxels), part by part, on the labels of 6 frames compiled here
/// and a share F of the voxels predicted as agents (a GPU step waits for this work between its
/// forward and its backward pass).
pub fn bench_loss(args: &[String]) {
    use rocc::backend::grounded::loss::{class_counts, flags, lovasz_rows, lovasz_weights, present_classes};
    let claimed: Vec<f64> =
        opt(args, "--claimed").unwrap_or("0.01,0.1").split(',').filter_map(|s| s.parse().ok()).collect();
    println!("== loss: the host side of a GPU step's loss, `paper` batch 6 on full grids (median of 5)");
    let dir = std::env::temp_dir().join(format!("rocc-bench-loss-{}", std::process::id()));
    let frames = corpus(&dir).and_then(|c| rocc::learn::data::scan(&c).ok()).unwrap_or_default();
    let mut target = Vec::new();
    for s in frames.iter().take(6) {
        match rocc::learn::data::load(s) {
            Ok(f) => target.extend(f.labels.iter().copied()),
            Err(e) => return println!("  {e}"),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    let n = target.len();
    if n == 0 {
        return println!("  the corpus did not compile");
    }
    let agents = target.iter().filter(|&&t| t >= 2).count();
    println!("  {n} voxels, {:.2} % of them agents in the truth", 100.0 * agents as f64 / n as f64);
    let mut rng = rocc::sample::Rng::new(1);
    for f in claimed {
        let predicted: Vec<bool> = (0..n).map(|_| rng.unit() < f).collect();
        let read_back = burn::tensor::TensorData::new(predicted.clone(), [n]);
        let draws: Vec<usize> = (0..20_000).map(|_| rng.index(n)).collect();
        let t_flags = median(5, || drop(std::hint::black_box(flags(&read_back))));
        let t_counts = median(5, || {
            std::hint::black_box(class_counts(&target));
        });
        let mut rows = Vec::new();
        let t_rows = median(5, || rows = lovasz_rows(&target, predicted.clone(), &draws));
        let sel: Vec<u8> = rows.iter().map(|&v| target[v]).collect();
        let present = present_classes(&sel);
        let probs: Vec<f32> = (0..sel.len() * present.len()).map(|_| rng.unit() as f32 / 4.5).collect();
        let t_weights = median(5, || drop(std::hint::black_box(lovasz_weights(&probs, &sel, &present))));
        println!(
            "  predicted agents {:>4.1} %: flags read back {:.1} ms, class counts {:.1}, Lovász rows {:.1} (m = {}), Lovász weights ({} classes) {:.1}; {:.1} ms in all",
            f * 100.0,
            t_flags * 1e3,
            t_counts * 1e3,
            t_rows * 1e3,
            rows.len(),
            present.len(),
            t_weights * 1e3,
            (t_flags + t_counts + t_rows + t_weights) * 1e3
        );
    }
}

/// `bench grounded [--device cpu|wgpu|cuda] [--batch N] [--configs a,b] [--precision full|mixed]`:
/// inference time per frame of each config on one device, `batch` frames of the ambulance example
/// per forward pass.
pub fn bench_grounded(args: &[String]) {
    use rocc::backend::grounded::{FrameIn, GBox, Generator, Grounded, latents};
    let opt = |name: &str| opt(args, name);
    let kind: DeviceKind = match opt("--device").unwrap_or("cpu").parse() {
        Ok(k) => k,
        Err(e) => return println!("  {e}"),
    };
    let batch: usize = opt("--batch").and_then(|b| b.parse().ok()).unwrap_or(kind.default_batch()).max(1);
    let configs = opt("--configs").unwrap_or("cpu-small,paper");
    let precision = match precision(args) {
        Ok(p) => p,
        Err(e) => return println!("  {e}"),
    };
    if let Err(d) = kind.open().and_then(|device| rocc::backend::grounded::attention::check(&precision, &device)) {
        return println!("  {} {}", d.code, d.message);
    }
    println!(
        "== grounded: inference per frame on {kind}, {} precision (batch {batch}; random weights)",
        precision.name()
    );
    let Some(f) = load(&root().join("scenarios/ambulance_crowded_intersection.scn")) else { return };
    let ego = f.concrete.egos.first().copied().unwrap_or(0);
    let mut raster = Rasterizer::new();
    let frames: Vec<(Vec<GBox>, Bev)> = (0..batch)
        .map(|n| {
            let fr = (n * 5).min(f.tracks.frames.saturating_sub(1));
            let boxes = frame_boxes(&f, ego, fr);
            let mut bev = Bev::zeros();
            raster.rasterize_into(&f.map, f.tracks.poses[ego][fr], &boxes, &mut bev);
            (boxes.iter().map(GBox::from_ego).collect(), bev)
        })
        .collect();
    let inputs: Vec<FrameIn> =
        frames.iter().map(|(b, bev)| FrameIn { boxes: b.clone(), masks: &bev.masks, aux: &bev.aux }).collect();
    for name in configs.split(',') {
        let cfg = match config(name) {
            Ok(c) => c,
            Err(e) => {
                println!("  {name}: {e}");
                continue;
            }
        };
        let set = latents::build(&cfg, &inputs[0].boxes, inputs[0].masks);
        let fg = set.iter().filter(|a| a.foreground).count();
        let mut model = Generator::new(&cfg, &rocc::backend::grounded::cpu());
        if model.bg_out.is_some() {
            // The background head starts at zero; random weights make it speak, so the CPU's
            // labels take the gate's softmax where free and background are close, as trained
            // weights do.
            let shape = [cfg.bev_features(), rocc::backend::layout::NZ];
            model.bg_out = Some(burn::nn::conv::Conv2dConfig::new(shape, [1, 1]).init(&rocc::backend::grounded::cpu()));
        }
        let on_cpu = Grounded::from_model(cfg.clone(), model.clone(), name);
        let mut g = match Grounded::from_model(cfg.clone(), model, name).on(kind, batch) {
            Ok(g) => g,
            Err(d) => return println!("  {name}: {} {}", d.code, d.message),
        };
        g.model.decoder.shape.precision = precision.clone();
        let run = || g.predict_frames(&inputs).map(|l| std::hint::black_box(l.len()));
        if let Err(d) = run() {
            println!("  {name:<10} {} {}", d.code, d.message);
            continue;
        }
        let reps = if name == "paper" && !kind.is_gpu() { 1 } else { 5 };
        let cpu0 = cpu_secs().unwrap_or(f64::NAN);
        let t = median(reps, || {
            let _ = run();
        });
        let cpu = (cpu_secs().unwrap_or(f64::NAN) - cpu0) / (reps * batch) as f64;
        println!(
            "  {name:<10} {:>5} latents ({fg} foreground), {:>8} parameters: {:>9.1} ms per frame, {:.1} CPU ms",
            set.len(),
            burn::module::Module::num_params(&g.model),
            t * 1e3 / batch as f64,
            cpu * 1e3
        );
        if kind.is_gpu() {
            // Float sums run in another order on a GPU: how many labels of the first frame match.
            let here = on_cpu.predict(&inputs[0].boxes, inputs[0].masks, inputs[0].aux);
            if let Ok(there) = g.predict_frames(&inputs[..1]) {
                let same = here.iter().zip(there[0].iter()).filter(|(a, b)| a == b).count();
                println!("  {name:<10} labels equal to the CPU's: {:.4} %", 100.0 * same as f64 / here.len() as f64);
            }
        }
    }
}
