//! Parameter checking and parsing shared by the procedural scenes. Every failure is an
//! [`Error::InvalidParameter`] named `scene.key` (e.g. `forest.trees`) that states the valid
//! range, so a bad `builtin:forest?trees=0` and a bad `ForestParams { trees: 0, .. }` read alike.

use std::str::FromStr;

use crate::{Error, Result};

/// The most triangles a procedural scene may have: about 2 GiB of vertices and indices. A larger
/// request is an error with the count, not an allocation failure.
pub const MAX_TRIANGLES: u64 = 32_000_000;

fn invalid(scene: &str, key: &str, value: impl ToString, reason: String) -> Error {
    Error::InvalidParameter { name: format!("{scene}.{key}"), value: value.to_string(), reason }
}

/// `lo ≤ v ≤ hi`.
pub(crate) fn check_u32(scene: &str, key: &str, v: u32, lo: u32, hi: u32) -> Result<()> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(invalid(scene, key, v, format!("expected an integer in {lo}..={hi}")))
    }
}

/// `v` finite and in [`lo`, `hi`], or in (0, `hi`] when `lo` is 0 (a size that must be positive).
pub(crate) fn check_f32(scene: &str, key: &str, v: f32, lo: f32, hi: f32) -> Result<()> {
    let ok = v.is_finite() && v <= hi && if lo == 0.0 { v > 0.0 } else { v >= lo };
    if ok {
        Ok(())
    } else if lo == 0.0 {
        Err(invalid(scene, key, v, format!("expected a number in (0, {hi}]")))
    } else {
        Err(invalid(scene, key, v, format!("expected a number in [{lo}, {hi}]")))
    }
}

/// The scene's triangle count is at most [`MAX_TRIANGLES`].
pub(crate) fn check_triangles(scene: &str, count: u64) -> Result<()> {
    if count <= MAX_TRIANGLES {
        return Ok(());
    }
    let gib = count as f64 * 68.0 / (1u64 << 30) as f64; // ~2 vertices of 28 B + 12 B per triangle
    Err(invalid(
        scene,
        "triangles",
        count,
        format!("more than {MAX_TRIANGLES} triangles (about {gib:.1} GiB); lower the counts"),
    ))
}

/// Parses a number, naming the parameter and what was expected on failure.
pub(crate) fn parse<T: FromStr>(scene: &str, key: &str, value: &str) -> Result<T> {
    value.trim().parse().map_err(|_| {
        let what = if std::any::type_name::<T>().starts_with('f') {
            "a number"
        } else {
            "a non-negative integer"
        };
        invalid(scene, key, value, format!("expected {what}"))
    })
}

/// Parses `true`/`false` (also `1`/`0`, `yes`/`no`, `on`/`off`).
pub(crate) fn parse_bool(scene: &str, key: &str, value: &str) -> Result<bool> {
    match value.trim().to_ascii_lowercase().as_str() {
        "true" | "1" | "yes" | "on" => Ok(true),
        "false" | "0" | "no" | "off" => Ok(false),
        _ => Err(invalid(scene, key, value, "expected true or false".into())),
    }
}

/// An unknown key of `scene`, listing the valid ones.
pub(crate) fn unknown(scene: &str, key: &str, value: &str, valid: &[&str]) -> Error {
    let reason = if valid.is_empty() {
        format!("unknown parameter: '{scene}' takes none")
    } else {
        format!("unknown parameter; '{scene}' takes: {}", valid.join(", "))
    };
    invalid(scene, key, value, reason)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_parameter_and_its_range() {
        let e = check_u32("forest", "trees", 0, 1, 100).unwrap_err().to_string();
        assert!(e.contains("forest.trees") && e.contains("1..=100") && e.contains("= 0"), "{e}");
        for bad in [f32::NAN, f32::INFINITY, 0.0, -1.0, 11.0] {
            let e = check_f32("s", "extent", bad, 0.0, 10.0).unwrap_err().to_string();
            assert!(e.contains("s.extent") && e.contains("(0, 10]"), "{e}");
        }
        check_f32("s", "extent", 10.0, 0.0, 10.0).unwrap();
        check_f32("s", "tilt", -80.0, -80.0, 80.0).unwrap();
        assert!(check_f32("s", "tilt", -80.5, -80.0, 80.0).is_err());
        let e = check_triangles("forest", MAX_TRIANGLES + 1).unwrap_err().to_string();
        assert!(e.contains("forest.triangles") && e.contains("GiB"), "{e}");
        check_triangles("forest", MAX_TRIANGLES).unwrap();
    }

    #[test]
    fn parsing_rejects_garbage_with_a_clear_reason() {
        assert_eq!(parse::<u32>("f", "trees", " 12 ").unwrap(), 12);
        assert_eq!(parse::<f32>("f", "extent", "2.5").unwrap(), 2.5);
        let e = parse::<u32>("f", "trees", "-3").unwrap_err().to_string();
        assert!(e.contains("f.trees") && e.contains("integer") && e.contains("-3"), "{e}");
        let e = parse::<f32>("f", "extent", "big").unwrap_err().to_string();
        assert!(e.contains("a number"), "{e}");
        assert!(parse_bool("f", "alpha", "Yes").unwrap());
        assert!(!parse_bool("f", "alpha", "0").unwrap());
        assert!(parse_bool("f", "alpha", "maybe").is_err());
        let e = unknown("forest", "tress", "3", &["trees", "seed"]).to_string();
        assert!(e.contains("forest.tress") && e.contains("trees, seed"), "{e}");
    }
}
