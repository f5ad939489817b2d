//! The CIREN case reader. In: a case directory (holding `crash_report.xml`) or the XML file
//! itself. Out: `CirenCase`, the coded fields rocc maps, as plain data with byte ranges into the
//! XML text so later diagnostics can point at the element they are about.
//!
//! The input is untrusted: the size is capped before anything is read, the text must be UTF-8,
//! and every field may be missing (it is `None` then; the mapping decides what it needs).

use crate::diag::Diagnostic;
use crate::source::{SourceMap, Span};
use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Largest case file rocc reads. Real CIREN records are 90-130 kB; the cap leaves room for
/// long narratives while refusing to load a stray multi-gigabyte file.
pub const MAX_CASE_BYTES: u64 = 16 * 1024 * 1024;

/// One coded field: NASS/CIREN writes `<Tag value="4" sasCode="R">Right Side</Tag>`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Coded {
    pub value: String,
    /// `sasCode` with its padding trimmed.
    pub sas: String,
    pub text: String,
    /// `UOM` where the field is a measurement (`kmph`).
    pub unit: String,
    /// Byte range of the element in the XML text.
    pub range: Range<usize>,
}

impl Coded {
    /// Lower-case text, for rule matching.
    pub fn lower(&self) -> String {
        self.text.to_ascii_lowercase()
    }
    /// The field as `Tag "text" (value N)`, for comments that cite the source.
    pub fn cite(&self, tag: &str) -> String {
        format!("{tag} \"{}\"", self.text)
    }
}

/// One row of `Events/EventSum`: vehicle `vehicle`'s damaged area, the party it contacted and
/// that party's damaged area.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Event {
    pub vehicle: u32,
    pub number: u32,
    pub rank: Option<u32>,
    pub class: Option<Coded>,
    pub area: Option<Coded>,
    pub contacted: Option<Coded>,
    pub contacted_class: Option<Coded>,
    pub contacted_area: Option<Coded>,
    pub range: Range<usize>,
}

/// The per-vehicle fields of `GeneralVehicleForm` (and `VehicleSum`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CaseVehicle {
    pub number: u32,
    pub year: Option<String>,
    pub make: Option<String>,
    pub model: Option<String>,
    pub body_type: Option<Coded>,
    pub travel_speed: Option<Coded>,
    pub posted_speed: Option<Coded>,
    pub relation_to_junction: Option<Coded>,
    pub relation_to_flow: Option<Coded>,
    pub travel_lanes: Option<Coded>,
    pub alignment: Option<Coded>,
    pub preevent_movement: Option<Coded>,
    pub critical_event: Option<Coded>,
    pub traffic_control: Option<Coded>,
    /// `Rollover/Data/Type`.
    pub rollover: Option<Coded>,
    /// `Vehicle/CurbWeight` (kg).
    pub curb_weight: Option<Coded>,
    pub range: Range<usize>,
}

/// One CDC row of a `VehicleExteriorForm`: the clock direction of the principal force on
/// `vehicle` in event `event`, and the total delta-V the reconstruction coded for it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CdcRow {
    pub vehicle: u32,
    pub event: u32,
    /// 1..=12; `None` when not coded (or out of range).
    pub clock: Option<u32>,
    /// `ComputerGeneratedDeltaV/Total` (999 = unknown: the mapping decides).
    pub delta_v: Option<Coded>,
    /// The `CDCevent` element.
    pub range: Range<usize>,
}

/// What rocc reads of one CIREN case record.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CirenCase {
    /// `CaseID`, or the directory name.
    pub id: String,
    /// The file as the user named it (for messages and comments).
    pub path: String,
    pub crash_type: Option<Coded>,
    pub configuration: Option<Coded>,
    pub summary: Option<Coded>,
    pub events: Vec<Event>,
    pub vehicles: Vec<CaseVehicle>,
    /// The CDC rows of every inspected vehicle.
    pub cdc: Vec<CdcRow>,
}

/// The XML file of a case: `PATH` itself, or `PATH/crash_report.xml` for a case directory.
pub fn case_file(path: &Path) -> PathBuf {
    if path.is_dir() { path.join("crash_report.xml") } else { path.to_path_buf() }
}

/// Read a file of at most `max` bytes as UTF-8 text; the message says what is wrong.
pub fn read_capped(path: &Path, max: u64) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    if meta.is_dir() {
        return Err(format!("`{}` is a directory", path.display()));
    }
    if meta.len() > max {
        return Err(format!("`{}` is {} bytes; rocc reads case files up to {} bytes", path.display(), meta.len(), max));
    }
    // The length can change between the check and the read (a growing file, a device): never
    // read more than the cap plus one byte, whatever the metadata said.
    let f = std::fs::File::open(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let mut bytes = Vec::new();
    f.take(max + 1).read_to_end(&mut bytes).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    if bytes.len() as u64 > max {
        return Err(format!("`{}` is larger than {} bytes", path.display(), max));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!("`{}` is not UTF-8 text (invalid byte at offset {})", path.display(), e.utf8_error().valid_up_to())
    })
}

/// Read and parse a case. The XML text is added to `sources` (its id is returned) so every
/// later diagnostic can label the element it is about.
pub fn read_case(path: &Path, sources: &mut SourceMap) -> Result<(CirenCase, u32), Vec<Diagnostic>> {
    let file = case_file(path);
    let text = read_capped(&file, MAX_CASE_BYTES).map_err(|m| {
        vec![
            Diagnostic::error("E0800", m)
                .help("pass a CIREN case directory holding `crash_report.xml`, or the XML file"),
        ]
    })?;
    let id = sources.add(file.display().to_string(), text.clone());
    let case = parse_case(&text, &file, id)?;
    Ok((case, id))
}

/// Parse case XML text (file id `file` in the source map, for spans).
pub fn parse_case(text: &str, path: &Path, file: u32) -> Result<CirenCase, Vec<Diagnostic>> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let pos = e.pos();
        let off = offset(text, pos.row as usize, pos.col as usize);
        vec![
            Diagnostic::error("E0801", format!("`{}` is not well-formed XML: {e}", path.display()))
                .label(Span::new(file, off, (off + 1).min(text.len()).max(off)), "here")
                .help("a CIREN case record is the NHTSA XML export (`crash_report.xml`); re-export or repair it"),
        ]
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "Case" {
        let r = root.range();
        return Err(vec![
            Diagnostic::error("E0802", format!("`{}` is XML but not a CIREN case record", path.display()))
                .label(Span::new(file, r.start, r.start + root.tag_name().name().len() + 1), "root element")
                .help("the root element of a CIREN record is `<Case CaseID=...>`"),
        ]);
    }
    let dir_name = path.parent().and_then(|p| p.file_name()).and_then(|n| n.to_str()).unwrap_or("case");
    let id = root.attribute("CaseID").map(str::trim).filter(|s| !s.is_empty()).unwrap_or(dir_name);
    let case_form = child(root, "CaseForm");
    let summary_node = case_form.and_then(|c| child(c, "CaseSummary"));
    let mut case = CirenCase {
        id: sanitize_id(id),
        path: path.display().to_string(),
        crash_type: summary_node.and_then(|s| child(s, "CrashType")).map(coded),
        configuration: summary_node.and_then(|s| child(s, "Configuration")).map(coded),
        summary: summary_node.and_then(|s| child(s, "Summary")).map(coded),
        ..Default::default()
    };
    if let Some(events) = case_form.and_then(|c| child(c, "Events")) {
        for e in events.children().filter(|n| n.has_tag_name("EventSum")) {
            case.events.push(Event {
                vehicle: num_attr(e, "VehicleNumber").unwrap_or(0),
                number: num_attr(e, "EventNumber").unwrap_or(0),
                rank: child(e, "Rank").and_then(|r| r.text()).and_then(|t| t.trim().parse().ok()),
                class: child(e, "Class").map(coded),
                area: child(e, "AreaOfDamage").map(coded),
                contacted: child(e, "Contacted").map(coded),
                contacted_class: child(e, "ContactedClass").map(coded),
                contacted_area: child(e, "ContactedAreaOfDamage").map(coded),
                range: e.range(),
            });
        }
    }
    let sums: Vec<roxmltree::Node> = case_form
        .and_then(|c| child(c, "Vehicles"))
        .map(|v| v.children().filter(|n| n.has_tag_name("VehicleSum")).collect())
        .unwrap_or_default();
    for g in root.descendants().filter(|n| n.has_tag_name("GeneralVehicleForm")) {
        let number = num_attr(g, "VehicleNumber").unwrap_or(0);
        let sum = sums.iter().find(|s| num_attr(**s, "VehicleNumber") == Some(number));
        let sum_text = |tag: &str| {
            sum.and_then(|s| child(*s, tag))
                .and_then(|n| n.text())
                .map(|t| t.trim().to_string())
                .filter(|t| !t.is_empty())
        };
        let find = |path: &[&str]| descend(g, path).map(coded);
        case.vehicles.push(CaseVehicle {
            number,
            year: sum_text("Year"),
            make: sum_text("Make"),
            model: sum_text("Model"),
            body_type: find(&["Vehicle", "BodyType"]),
            travel_speed: find(&["OfficialRecords", "PoliceReport", "TravelSpeed"]),
            posted_speed: find(&["OfficialRecords", "PoliceReport", "PostedSpeedLimit"]),
            relation_to_junction: find(&["Precrash", "Trafficway", "RelationToJunction"]),
            relation_to_flow: find(&["Precrash", "Trafficway", "RelationToFlow"]),
            travel_lanes: find(&["Precrash", "Roadway", "TravelLanes"]),
            alignment: find(&["Precrash", "Roadway", "Alignment"]),
            preevent_movement: find(&["Driver", "PreeventMovement"]),
            critical_event: find(&["Driver", "CriticalPrecrashEvent"]),
            traffic_control: find(&["Precrash", "TrafficControlDevices", "Device"]),
            rollover: find(&["Rollover", "Data", "Type"]),
            curb_weight: find(&["Vehicle", "CurbWeight"]),
            range: g.range(),
        });
    }
    case.vehicles.sort_by_key(|v| v.number);
    case.cdc = cdc_rows(root);
    Ok(case)
}

/// The CDC rows: `VehicleExteriorForm/CDC/CDCevent`, clock from `ClockDirection`, else the
/// leading digits of the CDC code (`12FCEN4` -> 12).
fn cdc_rows(root: roxmltree::Node) -> Vec<CdcRow> {
    let mut out = Vec::new();
    for f in root.descendants().filter(|n| n.has_tag_name("VehicleExteriorForm")) {
        let vehicle = num_attr(f, "VehicleNumber").unwrap_or(0);
        for e in f.descendants().filter(|n| n.has_tag_name("CDCevent")) {
            let text = |tag: &str| child(e, tag).and_then(|n| n.text()).map(str::trim).unwrap_or("");
            let lead = |t: &str| t.chars().take_while(char::is_ascii_digit).collect::<String>();
            let clock = [lead(text("ClockDirection")), lead(text("Summary"))]
                .iter()
                .find_map(|t| t.parse::<u32>().ok().filter(|h| (1..=12).contains(h)));
            out.push(CdcRow {
                vehicle,
                event: num_attr(e, "eventNumber").unwrap_or(0),
                clock,
                delta_v: descend(e, &["ComputerGeneratedDeltaV", "Total"]).map(coded),
                range: e.range(),
            });
        }
    }
    out
}

/// Case ids become file and scenario names: keep them to `[A-Za-z0-9_-]`.
fn sanitize_id(id: &str) -> String {
    let s: String = id.chars().take(64).map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect();
    if s.is_empty() { "case".into() } else { s }
}

fn child<'a, 'i>(n: roxmltree::Node<'a, 'i>, tag: &str) -> Option<roxmltree::Node<'a, 'i>> {
    n.children().find(|c| c.has_tag_name(tag))
}

fn descend<'a, 'i>(n: roxmltree::Node<'a, 'i>, path: &[&str]) -> Option<roxmltree::Node<'a, 'i>> {
    path.iter().try_fold(n, |n, tag| child(n, tag))
}

fn num_attr(n: roxmltree::Node, name: &str) -> Option<u32> {
    n.attribute(name).and_then(|v| v.trim().parse().ok())
}

fn coded(n: roxmltree::Node) -> Coded {
    let text: String = n.descendants().filter(|d| d.is_text()).filter_map(|d| d.text()).collect::<Vec<_>>().join("");
    Coded {
        value: n.attribute("value").unwrap_or("").trim().to_string(),
        sas: n.attribute("sasCode").unwrap_or("").trim().to_string(),
        text: text.split_whitespace().collect::<Vec<_>>().join(" "),
        unit: n.attribute("UOM").unwrap_or("").trim().to_string(),
        range: n.range(),
    }
}

/// Byte offset of a 1-based (line, column in characters) position, clamped to the text.
fn offset(text: &str, line: usize, col: usize) -> usize {
    let mut off = 0;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i + 1 == line {
            return off + l.char_indices().nth(col.saturating_sub(1)).map(|(b, _)| b).unwrap_or(l.len());
        }
        off += l.len();
    }
    text.len()
}
