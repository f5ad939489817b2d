//! `index.jsonl` at an output root: every finished clip and its frames (paths relative to the
//! root, timestamps, ego poses), JSON Lines: a header line, then one clip per line in (scenario,
//! ego) order, so a corpus index is written and read one clip at a time. A clip is finished when
//! its `manifest.json` parses and every file it lists exists with the listed size, the test a
//! resumed run applies; a clip being written has no manifest (it is removed first), so it is
//! never listed.
//!
//! The index is rebuilt from the tree, not patched, so batch compiles, resumes and shards all
//! leave it right. Concurrent shards each refresh at their end: `refresh` rewrites until a scan
//! taken after opening the file finds what the file says, so the last write is always followed
//! by a scan that saw every clip finished before it (docs/compile.md, "Dataset index").

use crate::fsio::{Fnv1a, input_hash, write_atomic};
use crate::output::{Manifest, read_ego_poses};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::{self, BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

/// The index's file name at the output root.
pub const INDEX_FILE: &str = "index.jsonl";
/// What `format` says.
pub const INDEX_FORMAT: &str = "rocc-index";
/// Rewrites before `refresh` gives up converging with concurrent writers (each one a full scan).
const MAX_ROUNDS: usize = 8;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Index {
    pub format: String,
    pub version: u32,
    /// Sorted by `dir`.
    pub clips: Vec<IndexClip>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexClip {
    /// `<scenario>/<ego>`, relative to the root.
    pub dir: String,
    pub scenario: String,
    pub ego: String,
    pub input: String,
    pub seed: u64,
    pub stage: String,
    pub rate_hz: f64,
    /// Frames of the whole clip; `frames` lists those written.
    pub frame_count: usize,
    /// `input_hash` of the clip's manifest without its timings: an unchanged manifest is not
    /// re-read.
    pub manifest_hash: String,
    pub boxes: String,
    /// `scene.json`, when the clip has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    pub frames: Vec<IndexFrame>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexFrame {
    pub frame: usize,
    /// Seconds since the clip start.
    pub t: f64,
    pub timestamp_us: u64,
    pub bev: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub occ: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lidar: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pcd: Option<String>,
    /// The ego's world pose `[x, y, z, yaw]` and 4x4 ego-to-world matrix (row-major), when
    /// `boxes.json` records them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<[f64; 4]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego2global: Option<[[f64; 4]; 4]>,
}

/// Read the whole of `root/index.jsonl` (a corpus index can be large: `IndexReader` streams it).
pub fn read_index(root: &Path) -> Result<Index, String> {
    let mut r = IndexReader::open(root)?;
    let mut clips = Vec::new();
    while let Some(c) = r.next_clip()? {
        clips.push(c);
    }
    Ok(Index { format: INDEX_FORMAT.to_string(), version: r.version, clips })
}

/// `index.jsonl` read one clip at a time, hashing every byte it reads.
pub struct IndexReader {
    path: PathBuf,
    lines: io::Lines<BufReader<File>>,
    pub version: u32,
    hash: Fnv1a,
    /// The clip read but not yet taken by `take`.
    pending: Option<IndexClip>,
}

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
}

impl IndexReader {
    pub fn open(root: &Path) -> Result<IndexReader, String> {
        let path = root.join(INDEX_FILE);
        let f = File::open(&path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
        let mut r =
            IndexReader { path, lines: BufReader::new(f).lines(), version: 0, hash: Fnv1a::new(), pending: None };
        let head = r.line()?.ok_or_else(|| format!("`{}` is empty", r.path.display()))?;
        let h: Header = serde_json::from_str(&head).map_err(|e| format!("`{}`: {e}", r.path.display()))?;
        if h.format != INDEX_FORMAT {
            return Err(format!("`{}` is not a rocc index (format `{}`)", r.path.display(), h.format));
        }
        r.version = h.version;
        Ok(r)
    }

    fn line(&mut self) -> Result<Option<String>, String> {
        match self.lines.next() {
            None => Ok(None),
            Some(Err(e)) => Err(format!("cannot read `{}`: {e}", self.path.display())),
            Some(Ok(l)) => {
                self.hash.write(l.as_bytes()).write(b"\n");
                Ok(Some(l))
            }
        }
    }

    /// The next clip, in the file's order.
    pub fn next_clip(&mut self) -> Result<Option<IndexClip>, String> {
        if let Some(c) = self.pending.take() {
            return Ok(Some(c));
        }
        let Some(l) = self.line()? else { return Ok(None) };
        serde_json::from_str(&l).map(Some).map_err(|e| format!("`{}`: {e}", self.path.display()))
    }

    /// The entry of clip `key` (scenario, ego), skipping the ones before it; the file is in
    /// key order, as `scan` writes it.
    fn take(&mut self, key: (&str, &str)) -> Option<IndexClip> {
        while let Ok(Some(c)) = self.next_clip() {
            match (c.scenario.as_str(), c.ego.as_str()).cmp(&key) {
                std::cmp::Ordering::Less => continue,
                std::cmp::Ordering::Equal => return Some(c),
                std::cmp::Ordering::Greater => {
                    self.pending = Some(c);
                    return None;
                }
            }
        }
        None
    }

    /// FNV-1a of the whole file, read to its end.
    fn finish(mut self) -> u64 {
        while let Ok(Some(_)) = self.line() {}
        self.hash.finish()
    }
}

/// Rebuild `root/index.jsonl` from the clips finished under `root` (see the module comment).
/// Returns the number of clips listed.
pub fn refresh(root: &Path) -> io::Result<usize> {
    let mut n = 0;
    for _ in 0..MAX_ROUNDS {
        // First pass: what the index would say now, hashed, against what the file says.
        let mut old = IndexReader::open(root).ok();
        let mut hash = Fnv1a::new();
        n = scan(root, old.as_mut(), &mut |b| {
            hash.write(b);
            Ok(())
        })?;
        if old.map(IndexReader::finish) == Some(hash.finish()) {
            return Ok(n);
        }
        let mut old = IndexReader::open(root).ok();
        write_atomic(&root.join(INDEX_FILE), |w| scan(root, old.as_mut(), &mut |b| w.write_all(b)).map(|_| ()))?;
    }
    Ok(n)
}

/// After a clip in `clip_dir` (`ROOT/<scenario>/<ego>`) changed outside a batch (`rocc edit`):
/// refresh `ROOT`'s index if it has one; a directory without an index is left without one.
pub fn refresh_root_of(clip_dir: &Path) -> Result<(), crate::diag::Diagnostic> {
    let Some(root) = clip_dir.parent().and_then(Path::parent) else { return Ok(()) };
    let root = if root.as_os_str().is_empty() { Path::new(".") } else { root };
    let path = root.join(INDEX_FILE);
    if !path.is_file() {
        return Ok(());
    }
    refresh(root).map(|_| ()).map_err(|e| {
        crate::diag::Diagnostic::error("E0410", format!("cannot write `{}`: {e}", path.display())).help(
            "the clip is written; fix the cause and re-run `rocc compile` into the same root to rebuild the index",
        )
    })
}

/// Stream the index of the clips finished under `root` now into `out`, one line each after the
/// header; entries of `prev` whose manifest is unchanged are reused without reading `boxes.json`
/// again. Returns the number of clips.
pub fn scan(
    root: &Path,
    mut prev: Option<&mut IndexReader>,
    out: &mut dyn FnMut(&[u8]) -> io::Result<()>,
) -> io::Result<usize> {
    put(&Header { format: INDEX_FORMAT.to_string(), version: 1 }, out)?;
    let mut n = 0;
    for scenario in sorted_dirs(root)? {
        for ego in sorted_dirs(&root.join(&scenario))? {
            let old = prev.as_deref_mut().and_then(|p| p.take((&scenario, &ego)));
            if let Some(c) = finished_clip(root, &scenario, &ego, old) {
                put(&c, out)?;
                n += 1;
            }
        }
    }
    Ok(n)
}

/// One line of the index.
fn put<T: Serialize>(v: &T, out: &mut dyn FnMut(&[u8]) -> io::Result<()>) -> io::Result<()> {
    let mut b = serde_json::to_vec(v).map_err(io::Error::other)?;
    b.push(b'\n');
    out(&b)
}

fn sorted_dirs(dir: &Path) -> io::Result<Vec<String>> {
    let mut out = Vec::new();
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(out),
        Err(e) => return Err(e),
    };
    for e in entries {
        let e = e?;
        if e.file_type()?.is_dir()
            && let Ok(name) = e.file_name().into_string()
        {
            out.push(name);
        }
    }
    out.sort();
    Ok(out)
}

/// The entry of the clip in `root/dir` if it is finished; `None` for anything else (no manifest,
/// another program's JSON, a listed file missing or of another size).
fn finished_clip(root: &Path, scenario: &str, ego: &str, old: Option<IndexClip>) -> Option<IndexClip> {
    let dir = format!("{scenario}/{ego}");
    let clip = root.join(&dir);
    let bytes = std::fs::read(clip.join("manifest.json")).ok()?;
    let m: Manifest = serde_json::from_slice(&bytes).ok()?;
    let files_ok = m
        .files
        .iter()
        .all(|f| std::fs::metadata(clip.join(&f.path)).is_ok_and(|md| md.is_file() && md.len() == f.bytes));
    if m.compiler != env!("CARGO_PKG_NAME") || !files_ok {
        return None;
    }
    // Timings left out: they are all that differs between two runs of the same input, and
    // the index is as deterministic as the clips.
    let hash = input_hash(&serde_json::to_vec(&Manifest { timings: Vec::new(), ..m.clone() }).ok()?);
    if let Some(c) = old.filter(|c| c.manifest_hash == hash) {
        return Some(c);
    }
    let listed: BTreeSet<&str> = m.files.iter().map(|f| f.path.as_str()).collect();
    let has = |p: String| listed.contains(p.as_str()).then(|| format!("{dir}/{p}"));
    let poses: BTreeMap<usize, crate::output::EgoRecord> = if listed.contains("boxes.json") {
        read_ego_poses(&clip.join("boxes.json")).ok()?.into_iter().map(|(f, _, e)| (f, e)).collect()
    } else {
        BTreeMap::new()
    };
    let frames = m
        .frames
        .iter()
        .map(|&f| {
            let ego = poses.get(&f);
            Some(IndexFrame {
                frame: f,
                t: f as f64 / m.rate_hz,
                timestamp_us: (f as f64 * 1e6 / m.rate_hz).round() as u64,
                bev: has(format!("bev/{f:06}.npz"))?,
                occ: has(format!("occ/{f:06}.npy")),
                lidar: has(format!("lidar/{f:06}.bin")),
                pcd: has(format!("lidar/{f:06}.pcd")),
                pose: ego.map(|e| [e.x, e.y, e.z, e.yaw]),
                ego2global: ego.map(|e| e.ego2global),
            })
        })
        .collect::<Option<Vec<_>>>()?;
    Some(IndexClip {
        dir: dir.clone(),
        scenario: scenario.to_string(),
        ego: ego.to_string(),
        input: m.input.clone(),
        seed: m.seed,
        stage: m.stage.clone(),
        rate_hz: m.rate_hz,
        frame_count: m.frame_count,
        manifest_hash: hash,
        boxes: format!("{dir}/boxes.json"),
        scene: has("scene.json".to_string()),
        frames,
    })
}
