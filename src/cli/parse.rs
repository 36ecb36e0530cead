//! Parsers for command-line values, used as clap `value_parser`s so that a bad value is
//! refused with the flag's name before a command runs: numbers in ranges, powers of two,
//! vectors `x,y,z`, sizes `WxH`, cameras and lights given as `key=value;key=value` lists. Each
//! error names the value and the expected form.
//!
//! Camera and light positions are world coordinates, read in `f64` and moved into a scene's
//! local coordinates by subtracting its origin (`voxlod_scene::Scene::origin`), so that a camera
//! placed at 10⁷ (where `f32` is spaced by 1) keeps its digits.

use anyhow::{Context, Result, anyhow, bail};
use glam::{DVec3, Vec3};
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

/// An export's output path, its format named by its extension (`.vox`, `.vol` or `.nvdb`).
pub fn export_output(s: &str) -> Result<super::ExportOutput, String> {
    let path = std::path::PathBuf::from(s);
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let format = match ext.as_deref() {
        Some("vox") => super::ExportFormat::Vox,
        Some("vol") => super::ExportFormat::Vol,
        Some("nvdb") => super::ExportFormat::Nvdb,
        _ => {
            return Err(format!(
                "'{s}' must end in .vox (MagicaVoxel), .vol (Mitsuba 3) or .nvdb (NanoVDB)"
            ));
        }
    };
    Ok(super::ExportOutput { path, format })
}

/// An image size `WxH` for clap (see [`size`]).
pub fn size_arg(s: &str) -> Result<(u32, u32), String> {
    size(s).map_err(|e| format!("{e:#}"))
}

/// A light for clap (see [`light`]).
pub fn light_arg(s: &str) -> Result<LightSpec, String> {
    light(s).map_err(|e| format!("{e:#}"))
}

/// A light as given on the command line, in world coordinates: [`LightSpec::in_scene`] places
/// it in a scene's local coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSpec {
    /// The light, a point light's position rounded to `f32` (validated).
    light: Light,
    /// A point light's world position in `f64`.
    point: Option<DVec3>,
}

impl LightSpec {
    /// The light in the local coordinates of a scene whose origin is `origin`: a point light's
    /// position is `world − origin`, subtracted in `f64`; a direction does not move.
    pub fn in_scene(&self, origin: DVec3) -> Light {
        match (self.light, self.point) {
            (Light::Point { intensity, .. }, Some(p)) => {
                Light::Point { position: (p - origin).as_vec3(), intensity }
            }
            (light, _) => light,
        }
    }
}

/// Parses `x,y,z` in `f64` (world positions).
pub fn dvec3(s: &str) -> Result<DVec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        bail!("'{s}' is not a vector: expected three comma-separated numbers like 1,2.5,-3");
    }
    let mut v = [0.0f64; 3];
    for (dst, p) in v.iter_mut().zip(&parts) {
        *dst = p.parse().with_context(|| format!("'{p}' in '{s}' is not a number"))?;
        if !dst.is_finite() {
            bail!("'{p}' in '{s}' is not finite");
        }
    }
    Ok(DVec3::from_array(v))
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
/// (the scene's default camera, in its local coordinates) for keys not given. `eye` and
/// `target` are world positions: `origin` (the scene's) is subtracted from them in `f64`.
pub fn camera(s: &str, base: Camera, origin: DVec3) -> Result<Camera> {
    let mut cam = base;
    for (k, v) in pairs(s, "camera", &["eye", "target", "up", "fov"])? {
        let field = || format!("camera {k}={v}");
        let local = |v: &str| dvec3(v).map(|w| (w - origin).as_vec3()).with_context(field);
        match k {
            "eye" => cam.eye = local(v)?,
            "target" => cam.target = local(v)?,
            "up" => cam.up = vec3(v).with_context(field)?,
            _ => cam.fov_y_deg = v.parse().with_context(|| format!("fov '{v}' is not a number"))?,
        }
    }
    cam.validate().with_context(|| format!("camera '{s}'"))?;
    Ok(cam)
}

/// Parses a light: `dir=X,Y,Z[;irradiance=R,G,B or E]` (direction toward the light) or
/// `point=X,Y,Z[;intensity=R,G,B or I]`.
pub fn light(s: &str) -> Result<LightSpec> {
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
    let (light, point) = match (get("dir"), get("point")) {
        (Some(d), None) => (
            Light::Directional {
                to_light: vec3(d)?,
                irradiance: get("irradiance").map(color).transpose()?.unwrap_or(Vec3::splat(3.0)),
            },
            None,
        ),
        (None, Some(p)) => {
            let point = dvec3(p)?;
            let light = Light::Point {
                position: point.as_vec3(),
                intensity: get("intensity").map(color).transpose()?.unwrap_or(Vec3::splat(30.0)),
            };
            (light, Some(point))
        }
        _ => bail!("light '{s}' must give exactly one of dir=X,Y,Z or point=X,Y,Z"),
    };
    let light = light.validated().with_context(|| format!("light '{s}'"))?;
    Ok(LightSpec { light, point })
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
        let c = camera("eye=0,0,5;fov=30", base, DVec3::ZERO).unwrap();
        assert_eq!((c.eye, c.fov_y_deg), (Vec3::new(0.0, 0.0, 5.0), 30.0));
        assert!(camera("eye=0,0,0", base, DVec3::ZERO).is_err(), "eye at target");
        assert!(camera("zoom=2", base, DVec3::ZERO).unwrap_err().to_string().contains("zoom"));
        let point = light("point=0,5,0;intensity=10").unwrap().in_scene(DVec3::ZERO);
        assert!(
            matches!(point, Light::Point { position, .. } if position == Vec3::new(0.0, 5.0, 0.0))
        );
        assert!(light("dir=0,1,0;point=1,1,1").is_err());
        assert!(light("dir=0,0,0").is_err());
    }

    #[test]
    fn world_positions_keep_their_digits_far_from_the_origin() {
        // f32 spaces numbers by 1 at 10⁷: 10000000.25 would read as 10⁷.
        let origin = DVec3::new(1e7, -2e6, 0.0);
        let base = Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0);
        let c = camera("eye=10000000.25,-2000000,5;target=10000000,-1999999.5,0", base, origin)
            .unwrap();
        assert_eq!((c.eye, c.target), (Vec3::new(0.25, 0.0, 5.0), Vec3::new(0.0, 0.5, 0.0)));
        let l = light("point=10000000.5,-2000000,3").unwrap().in_scene(origin);
        assert!(matches!(l, Light::Point { position, .. } if position == Vec3::new(0.5, 0.0, 3.0)));
        // A direction is not a position: the origin does not move it.
        let d = light("dir=0,1,0").unwrap();
        assert_eq!(d.in_scene(origin), d.in_scene(DVec3::ZERO));
    }
}
