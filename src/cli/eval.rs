//! `rocc eval occ | lidar | edits`: the shared scorers over two directories, and the edit
//! protocol; a table on stdout, or JSON.

use super::Failure;
use clap::Subcommand;
use serde::Serialize;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum EvalCmd {
    /// Per-class occupancy IoU over a set, mIoU_US, fg-mIoU, occ-IoU.
    Occ {
        #[arg(long)]
        pred: PathBuf,
        #[arg(long)]
        gt: PathBuf,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// LiDAR MMD and JSD between two sets of clouds.
    Lidar {
        /// Compiled clip directories (their lidar/ frames), or directories of .bin / .pcd / .npy clouds.
        #[arg(long)]
        pred: PathBuf,
        /// As `--pred`.
        #[arg(long)]
        gt: PathBuf,
        /// Keep only points with 3 < range < 50 m.
        #[arg(long)]
        range_filter: bool,
        #[arg(long)]
        json: bool,
    },
    /// The paper's edit protocol (insert / delete / move) on the procedural backend.
    Edits {
        #[arg(long, default_value_t = 100)]
        scenes: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Scenarios to draw scenes from.
        #[arg(long, default_value = "scenarios")]
        scenarios: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

pub fn run(what: EvalCmd) -> Result<(), Failure> {
    match what {
        EvalCmd::Occ { pred, gt, json } => {
            let s = rocc::eval::score_occ_dirs(&pred, &gt)?;
            if json { print_json(&s) } else { out!("{}", s.table()) }
        }
        EvalCmd::Lidar { pred, gt, range_filter, json } => {
            let s = rocc::eval::score_lidar_dirs(&pred, &gt, range_filter)?;
            if json {
                return print_json(&s);
            }
            outln!(
                "MMD {:.4e} ({:.3} x 1e-5)   JSD {:.4}   ({} predicted vs {} ground-truth clouds{})",
                s.mmd,
                s.mmd * 1e5,
                s.jsd,
                s.pred_clouds,
                s.gt_clouds,
                if s.range_filter { ", 3 < r < 50 m" } else { "" }
            )
        }
        EvalCmd::Edits { scenes, seed, scenarios, json } => {
            let s = rocc::eval::run_edit_protocol(&scenarios, scenes, seed)?;
            if json { print_json(&s) } else { out!("{}", s.table()) }
        }
    }
}

fn print_json(scores: &impl Serialize) -> Result<(), Failure> {
    outln!("{}", serde_json::to_string_pretty(scores).expect("scores are plain numbers"))
}
