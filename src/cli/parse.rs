//! Parsers for command-line values, used as clap `value_parser`s so that a bad value is
//! refused with the flag's name before a command runs: numbers in ranges, powers of two,
//! vectors `x,y,z`, sizes `WxH`, cameras and lights given as `key=value;key=value` lists. Each
//! error names the value and the expected form.

use anyhow::{Context, Result, anyhow, bail};
use glam::Vec3;
use voxlod::scene::{Camera, Light};

/// A parser of `f32` values in `[lo, hi]` (`hi` excluded when `open_hi`); NaN and infinities
/// are refused.
pub fn f32_in(
    lo: f32,
    hi: f32,
    open_hi: bool,
) -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let v: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
        let inside = v >= lo && if open_hi { v < hi } else { v <= hi };
        if !v.is_finite() || !inside {
            let close = if open_hi { ')' } else { ']' };
            return Err(format!("{v} is not in [{lo}, {hi}{close}"));
        }
        Ok(v)
    }
}

/// A finite `f32` greater than zero.
pub fn positive_f32(s: &str) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("{v} is not finite and > 0"));
    }
    Ok(v)
}

/// A finite `f32` at least zero.
pub fn non_negative_f32(s: &str) -> Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(format!("{v} is not a finite non-negative number"));
    }
    Ok(v)
}

/// A power of two in 4..=1024 (an octree resolution).
pub fn octree_resolution(s: &str) -> Result<u32, String> {
    let v: u32 = s.trim().parse().map_err(|_| format!("'{s}' is not a whole number"))?;
    if !(v.is_power_of_two() && (4..=1024).contains(&v)) {
        return Err(format!("{v} is not a power of two in 4..=1024"));
    }
    Ok(v)
}

/// A whole number at least 1 (`usize`).
pub fn at_least_one(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(v) if v >= 1 => Ok(v),
        _ => Err(format!("'{s}' is not a whole number ≥ 1")),
    }
}

/// An export's output path, its format named by its extension (`.vox` or `.vol`).
pub fn export_output(s: &str) -> Result<super::ExportOutput, String> {
    let path = std::path::PathBuf::from(s);
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("vox") => super::ExportFormat::Vox,
        Some("vol") => super::ExportFormat::Vol,
        _ => return Err(format!("'{s}' must end in .vox (MagicaVoxel) or .vol (Mitsuba 3)")),
    };
    Ok(super::ExportOutput { path, format })
}

/// An image size `WxH` for clap (see [`size`]).
pub fn size_arg(s: &str) -> Result<(u32, u32), String> {
    size(s).map_err(|e| format!("{e:#}"))
}

/// A light for clap (see [`light`]).
pub fn light_arg(s: &str) -> Result<Light, String> {
    light(s).map_err(|e| format!("{e:#}"))
}

/// Parses `x,y,z`.
pub fn vec3(s: &str) -> Result<Vec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        bail!("'{s}' is not a vector: expected three comma-separated numbers like 1,2.5,-3");
    }
    let mut v = [0.0f32; 3];
    for (dst, p) in v.iter_mut().zip(&parts) {
        *dst = p.parse().with_context(|| format!("'{p}' in '{s}' is not a number"))?;
        if !dst.is_finite() {
            bail!("'{p}' in '{s}' is not finite");
        }
    }
    Ok(Vec3::from_array(v))
}

/// Parses `WxH` (e.g. `512x384`), each in 1..=16384.
pub fn size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| anyhow!("'{s}' is not an image size: expected WIDTHxHEIGHT like 512x512"))?;
    let parse = |t: &str| -> Result<u32> {
        let v: u32 =
            t.trim().parse().with_context(|| format!("'{t}' in '{s}' is not a whole number"))?;
        if !(1..=16384).contains(&v) {
            bail!("{v} in '{s}' is out of range: each side must be in 1..=16384");
        }
        Ok(v)
    };
    Ok((parse(w)?, parse(h)?))
}

/// Splits `k=v;k=v` into pairs, rejecting keys not in `allowed`.
fn pairs<'a>(s: &'a str, what: &str, allowed: &[&str]) -> Result<Vec<(&'a str, &'a str)>> {
    s.split(';')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .map(|p| {
            let (k, v) = p
                .split_once('=')
                .ok_or_else(|| anyhow!("'{p}' in {what} '{s}' is not key=value"))?;
            let k = k.trim();
            if !allowed.contains(&k) {
                bail!("unknown key '{k}' in {what} '{s}': expected one of {}", allowed.join(", "));
            }
            Ok((k, v.trim()))
        })
        .collect()
}

/// Parses a camera `eye=X,Y,Z;target=X,Y,Z[;up=X,Y,Z][;fov=DEGREES]`, starting from `base`
/// (the scene's default camera) for keys not given.
pub fn camera(s: &str, base: Camera) -> Result<Camera> {
    let mut cam = base;
    for (k, v) in pairs(s, "camera", &["eye", "target", "up", "fov"])? {
        let field = || format!("camera {k}={v}");
        match k {
            "eye" => cam.eye = vec3(v).with_context(field)?,
            "target" => cam.target = vec3(v).with_context(field)?,
            "up" => cam.up = vec3(v).with_context(field)?,
            _ => cam.fov_y_deg = v.parse().with_context(|| format!("fov '{v}' is not a number"))?,
        }
    }
    cam.validate().with_context(|| format!("camera '{s}'"))?;
    Ok(cam)
}

/// Parses a light: `dir=X,Y,Z[;irradiance=R,G,B or E]` (direction toward the light) or
/// `point=X,Y,Z[;intensity=R,G,B or I]`.
pub fn light(s: &str) -> Result<Light> {
    let kv = pairs(s, "light", &["dir", "irradiance", "point", "intensity"])?;
    let get = |key: &str| kv.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
    let color = |v: &str| -> Result<Vec3> {
        if v.contains(',') {
            vec3(v)
        } else {
            let x: f32 = v.parse().with_context(|| format!("'{v}' is not a number"))?;
            Ok(Vec3::splat(x))
        }
    };
    let light = match (get("dir"), get("point")) {
        (Some(d), None) => Light::Directional {
            to_light: vec3(d)?,
            irradiance: get("irradiance").map(color).transpose()?.unwrap_or(Vec3::splat(3.0)),
        },
        (None, Some(p)) => Light::Point {
            position: vec3(p)?,
            intensity: get("intensity").map(color).transpose()?.unwrap_or(Vec3::splat(30.0)),
        },
        _ => bail!("light '{s}' must give exactly one of dir=X,Y,Z or point=X,Y,Z"),
    };
    light.validated().with_context(|| format!("light '{s}'"))
}

/// An import's input path, its format named by its extension (`.vox` or `.vol`).
pub fn import_input(s: &str) -> Result<super::ImportInput, String> {
    let path = std::path::PathBuf::from(s);
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("vox") => super::ImportFormat::Vox,
        Some("vol") => super::ImportFormat::Vol,
        _ => return Err(format!("'{s}' must end in .vox (MagicaVoxel) or .vol (Mitsuba 3)")),
    };
    Ok(super::ImportInput { path, format })
}

/// A `.vxl` output path.
pub fn vxl_output(s: &str) -> Result<std::path::PathBuf, String> {
    let path = std::path::PathBuf::from(s);
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("vxl") => Ok(path),
        _ => Err(format!("'{s}' must end in .vxl")),
    }
}

/// A finite `f64` greater than zero.
pub fn positive_f64(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("{v} is not finite and > 0"));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_parse_and_errors_name_the_value() {
        assert_eq!(vec3("1, 2,-3.5").unwrap(), Vec3::new(1.0, 2.0, -3.5));
        assert!(vec3("1,2").unwrap_err().to_string().contains("'1,2'"));
        assert!(vec3("1,2,inf").is_err());
        assert_eq!(size("640x480").unwrap(), (640, 480));
        assert!(size("0x10").is_err());
        assert!(size("10").unwrap_err().to_string().contains("WIDTHxHEIGHT"));
        let base = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0);
        let c = camera("eye=0,0,5;fov=30", base).unwrap();
        assert_eq!((c.eye, c.fov_y_deg), (Vec3::new(0.0, 0.0, 5.0), 30.0));
        assert!(camera("eye=0,0,0", base).is_err(), "eye at target");
        assert!(camera("zoom=2", base).unwrap_err().to_string().contains("zoom"));
        assert!(matches!(light("point=0,5,0;intensity=10").unwrap(), Light::Point { .. }));
        assert!(light("dir=0,1,0;point=1,1,1").is_err());
        assert!(light("dir=0,0,0").is_err());
    }
}
