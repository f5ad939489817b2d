//! Recorded class names -> the nuPlan taxonomy (SPEC.md BEV channels 8-14) and a rocc kind.
//! nuPlan names map to themselves; nuScenes' and mmdet3d's as nuPlan groups them (two-wheelers,
//! motorcycles included, are `bicycle`; debris, pushables and animals are `generic_object`).
//! Unknown names become `generic_object`, flagged so the importer warns — never dropped.

use super::scenario::Class;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClassMap {
    pub class: Class,
    /// The stdlib kind the imported agent is declared with (its shape in the occupancy).
    pub kind: &'static str,
    pub known: bool,
}

pub fn map_class(name: &str) -> ClassMap {
    let n = name.trim().to_ascii_lowercase();
    let k = |class, kind| ClassMap { class, kind, known: true };
    use Class::*;
    match n.as_str() {
        "vehicle" | "car" | "vehicle.car" => k(Vehicle, "sedan"),
        "truck" | "vehicle.truck" | "trailer" | "vehicle.trailer" | "construction_vehicle" | "vehicle.construction" => {
            k(Vehicle, "truck")
        }
        "bus" | "vehicle.bus.bendy" | "vehicle.bus.rigid" => k(Vehicle, "bus"),
        "vehicle.emergency.ambulance" | "ambulance" => k(Vehicle, "ambulance"),
        "vehicle.emergency.police" | "police" => k(Vehicle, "police_car"),
        "bicycle" | "vehicle.bicycle" | "motorcycle" | "vehicle.motorcycle" | "cyclist" => k(Bicycle, "bicycle"),
        "pedestrian" | "human" => k(Pedestrian, "pedestrian"),
        "traffic_cone" | "movable_object.trafficcone" => k(TrafficCone, "traffic_cone"),
        "barrier" | "movable_object.barrier" => k(Barrier, "barrier"),
        "czone_sign" | "construction_sign" => k(CzoneSign, "construction_sign"),
        "generic_object"
        | "movable_object.debris"
        | "movable_object.pushable_pullable"
        | "static_object.bicycle_rack" => k(GenericObject, "debris"),
        "animal" => k(GenericObject, "animal"),
        _ if n.starts_with("human.pedestrian") => k(Pedestrian, "pedestrian"),
        _ if n.starts_with("vehicle.") => k(Vehicle, "sedan"),
        _ => ClassMap { class: GenericObject, kind: "debris", known: false },
    }
}
