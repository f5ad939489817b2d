//! Units by dimension. Every conversion to SI happens here, once.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    Length,
    Speed,
    Time,
    Angle,
    Frequency,
    /// `%`, or a bare fraction where a ratio is expected.
    Ratio,
    /// A bare number.
    Count,
}

impl Dim {
    pub fn name(self) -> &'static str {
        match self {
            Dim::Length => "a length",
            Dim::Speed => "a speed",
            Dim::Time => "a time",
            Dim::Angle => "an angle",
            Dim::Frequency => "a frequency",
            Dim::Ratio => "a ratio",
            Dim::Count => "a plain number",
        }
    }
    /// The units a user may write for this dimension (for hints).
    pub fn units(self) -> &'static str {
        match self {
            Dim::Length => "m, cm or km",
            Dim::Speed => "m/s, km/h or mph",
            Dim::Time => "s or ms",
            Dim::Angle => "deg or rad",
            Dim::Frequency => "Hz",
            Dim::Ratio => "%",
            Dim::Count => "no unit",
        }
    }
}

/// Dimension and factor to SI of a unit the grammar accepts.
pub fn unit(u: &str) -> (Dim, f64) {
    match u {
        "m" => (Dim::Length, 1.0),
        "cm" => (Dim::Length, 0.01),
        "km" => (Dim::Length, 1000.0),
        "m/s" => (Dim::Speed, 1.0),
        "km/h" => (Dim::Speed, 1.0 / 3.6),
        "mph" => (Dim::Speed, 0.44704),
        "s" => (Dim::Time, 1.0),
        "ms" => (Dim::Time, 0.001),
        "deg" => (Dim::Angle, std::f64::consts::PI / 180.0),
        "rad" => (Dim::Angle, 1.0),
        "Hz" => (Dim::Frequency, 1.0),
        "%" => (Dim::Ratio, 0.01),
        other => unreachable!("grammar: unit {other}"),
    }
}
