//! Units by dimension. Every conversion to SI happens here, once, and so do the hints that
//! name the unit a user likely meant.

use crate::syntax::ast;

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
    /// kg.
    Mass,
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
            Dim::Mass => "a mass",
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
            Dim::Mass => "kg",
        }
    }
}

/// Dimension and factor to SI of a unit the grammar accepts.
pub fn unit(u: &str) -> (Dim, f64) {
    lookup(u).unwrap_or_else(|| unreachable!("grammar: unit {u}"))
}

/// Dimension and factor to SI of a unit, or `None` for a word that is not one.
pub fn lookup(u: &str) -> Option<(Dim, f64)> {
    Some(match u {
        "m" => (Dim::Length, 1.0),
        "kg" => (Dim::Mass, 1.0),
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
        _ => return None,
    })
}

/// A hint naming the likely intended unit: the speed unit built from a length unit (`30 km` ->
/// `km/h`, `5 m` -> `m/s`) and the length unit a speed unit is built from.
pub fn hint(want: Dim, got: Dim, v: &ast::Value) -> String {
    let unit = v.unit.as_ref().map_or("", |u| u.text.as_str());
    match (want, got, unit) {
        (Dim::Speed, Dim::Length, "m") => "; a bare `m` is a length — did you mean `m/s`?".to_string(),
        (Dim::Speed, Dim::Length, "km") => "; `km` is a length — did you mean `km/h`?".to_string(),
        (Dim::Length, Dim::Speed, "m/s") => "; `m/s` is a speed — did you mean `m`?".to_string(),
        (Dim::Length, Dim::Speed, "km/h") => "; `km/h` is a speed — did you mean `km`?".to_string(),
        (Dim::Speed, Dim::Length, _) | (Dim::Length, Dim::Speed, _) => format!("; `{unit}` is {}", got.name()),
        (Dim::Time, Dim::Length, _) => "; `m` is metres, `ms` milliseconds, `s` seconds".to_string(),
        (Dim::Angle, _, _) => "; headings are angles, e.g. `90 deg`".to_string(),
        _ => String::new(),
    }
}

/// The value rewritten in the unit its bounds are shown in (`2.5..6 m`), when the written value
/// lies far out of bounds (beyond twice the upper or below half the lower) and the rewritten one
/// within them: `lane_width 3.5 km` is a slip for `3.5 m`, where `speed 120 mph` is just fast.
pub fn slip(v: &ast::Value, dim: Dim, min: f64, max: f64, shown: &str) -> Option<String> {
    let written = v.unit.as_ref()?;
    let (meant, factor) =
        shown.split_whitespace().find_map(|w| lookup(w).filter(|(d, _)| *d == dim).map(|(_, f)| (w, f)))?;
    let numbers: Vec<f64> = std::iter::once(v.lo.value).chain(v.hi.as_ref().map(|h| h.value)).collect();
    let written_factor = unit(&written.text).1;
    let far = |x: f64| {
        let si = x * written_factor;
        (max > 0.0 && si > 2.0 * max) || (min > 0.0 && si < 0.5 * min) || (min < 0.0 && si < 2.0 * min)
    };
    let fits = numbers.iter().all(|x| (min..=max).contains(&(x * factor)));
    let far = numbers.iter().any(|x| far(*x));
    let number = match &v.hi {
        Some(h) => format!("{}..{}", v.lo.literal, h.literal),
        None => v.lo.literal.clone(),
    };
    (meant != written.text && far && fits).then(|| format!("{number} {meant}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(number: &str, unit: &str) -> ast::Value {
        let span = crate::source::Span::new(0, 0, 0);
        let n = |s: &str| ast::Number { value: s.parse().expect("number"), literal: s.to_string() };
        ast::Value { lo: n(number), hi: None, unit: Some(ast::Unit { text: unit.to_string(), span }), span }
    }

    #[test]
    fn a_length_unit_where_a_speed_is_expected_names_the_speed_unit_built_from_it() {
        assert!(hint(Dim::Speed, Dim::Length, &value("30", "km")).contains("did you mean `km/h`?"));
        assert!(hint(Dim::Speed, Dim::Length, &value("5", "m")).contains("did you mean `m/s`?"));
        assert!(hint(Dim::Length, Dim::Speed, &value("3", "km/h")).contains("did you mean `km`?"));
        assert!(!hint(Dim::Speed, Dim::Length, &value("30", "cm")).contains("did you mean"));
    }

    #[test]
    fn a_value_far_out_of_range_that_fits_in_the_shown_unit_is_a_unit_slip() {
        assert_eq!(slip(&value("3.5", "km"), Dim::Length, 2.5, 6.0, "2.5..6 m").as_deref(), Some("3.5 m"));
        assert_eq!(slip(&value("5", "ms"), Dim::Time, 0.1, 120.0, "0.1..120 s").as_deref(), Some("5 s"));
        // Written in the shown unit already, or only a little too fast: no slip.
        assert_eq!(slip(&value("3600", "s"), Dim::Time, 0.1, 120.0, "0.1..120 s"), None);
        assert_eq!(slip(&value("250", "mph"), Dim::Speed, 0.0, 90.0, "0..324 km/h"), None);
        // Far out, but no better in the shown unit either.
        assert_eq!(slip(&value("90", "km"), Dim::Length, 2.5, 6.0, "2.5..6 m"), None);
    }
}
