//! `blinds`: venetian blinds in front of a striped wall — many thin, parallel, tilted slats,
//! spaced below a voxel. It isolates **directional opacity**, with a known answer: seen along the
//! slats the panel is almost transparent (a fraction `thickness / (spacing · cos tilt)` is
//! blocked), seen across them it is opaque, and from the front a fraction
//! `(chord · sin tilt + thickness · cos tilt) / spacing` is blocked. A voxel of the panel holds
//! the same geometry in every case; only the direction changes. An isotropic voxel (Averages:
//! opacity = hits / rays) must be wrong for most views; the opacity subgrid and the
//! non-exponential transmittance are judged by how close they come to that formula. The slats are
//! also **two-coloured** — glossy white (specular) on top, dark underneath — so the colour
//! seen depends on the direction too, which a single colour per voxel cannot show and the virtual
//! mesh's per-face colours can.
//!
//! Each slat is a closed thin box (12 triangles), `1.2 · spacing` deep, so that the blinds close
//! fully at 90°. Nothing is random: the scene is a function of its parameters only.

use glam::Vec3;

use super::builder::MeshBuilder;
use super::param::{check_f32, check_u32};
use super::rng::sin_cos_deg;
use crate::{Camera, Light, Material, Result, Scene};

/// Parameters of [`blinds`].
#[derive(Clone, Debug, PartialEq)]
pub struct BlindsParams {
    /// Number of slats, 2..=4 096, over a panel 0.75 · extent high (12 triangles each). Default
    /// 128: the spacing is 0.75 voxel at 128³.
    pub slats: u32,
    /// Tilt of the slats in degrees, −89..=89: 0 is horizontal (open), positive turns the top
    /// faces toward the camera (+z). Default 20: the camera, a little below the panel's middle,
    /// looks through its top rows edge-on and sees its bottom rows about 70 % closed.
    pub tilt_deg: f32,
    /// Width of the scene (x), 0.001..=1e6. Default 2.
    pub extent: f32,
}

impl Default for BlindsParams {
    fn default() -> Self {
        Self { slats: 128, tilt_deg: 20.0, extent: 2.0 }
    }
}

/// Slat geometry derived from the parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlatGeometry {
    /// Vertical distance between slat centres.
    pub spacing: f32,
    /// Depth of a slat across its width (along its tilted chord).
    pub chord: f32,
    /// Thickness: `min(extent / 1000, spacing / 4)`.
    pub thickness: f32,
    /// Height of the lowest slat centre.
    pub bottom: f32,
}

impl BlindsParams {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<()> {
        check_u32("blinds", "slats", self.slats, 2, 4096)?;
        check_f32("blinds", "tilt", self.tilt_deg, -89.0, 89.0)?;
        check_f32("blinds", "extent", self.extent, 1e-3, 1e6)
    }

    /// The slats' spacing, chord, thickness and lowest centre.
    pub fn slat_geometry(&self) -> SlatGeometry {
        let spacing = 0.75 * self.extent / self.slats as f32;
        SlatGeometry {
            spacing,
            chord: 1.2 * spacing,
            thickness: (self.extent / 1000.0).min(0.25 * spacing),
            bottom: 0.1 * self.extent + 0.5 * spacing,
        }
    }
}

/// Generates the blinds: meshes `blinds/wall` (8 vertical stripes in 4 colours), `blinds/floor`,
/// `blinds/slat_tops` (the glossy top faces) and `blinds/slats` (the other faces), a light from
/// the front and above, and a camera a little below the panel's middle and to the side, whose
/// view spans elevations from −8° to +20°: from mostly closed to edge-on.
pub fn blinds(p: &BlindsParams) -> Result<Scene> {
    p.validate()?;
    let w = p.extent;
    let g = p.slat_geometry();
    let (s, c) = sin_cos_deg(p.tilt_deg);
    // Slat frame: x along the slat, n its top normal, u = x × n its chord (front edge).
    let n = Vec3::new(0.0, c, s);
    let axes = [Vec3::X, n, Vec3::X.cross(n)];
    let half = Vec3::new(0.45 * w, 0.5 * g.thickness, 0.5 * g.chord);
    let slats = p.slats as usize;
    let mut tops = MeshBuilder::with_capacity(4 * slats, 2 * slats, true);
    let mut rest = MeshBuilder::with_capacity(20 * slats, 10 * slats, true);
    for k in 0..p.slats {
        let center = Vec3::new(0.0, g.bottom + k as f32 * g.spacing, 0.0);
        tops.oriented_box(center, axes, half, 0b00_0100);
        rest.oriented_box(center, axes, half, 0b11_1011);
    }
    let mut wall: Vec<MeshBuilder> =
        (0..4).map(|_| MeshBuilder::with_capacity(8, 4, true)).collect();
    for i in 0..8 {
        let corner = Vec3::new(-0.5 * w + i as f32 * w / 8.0, 0.0, -0.3 * w);
        wall[i % 4].flat_quad(corner, Vec3::X * (w / 8.0), Vec3::Y * (0.95 * w));
    }
    let mut floor = MeshBuilder::with_capacity(4, 2, true);
    floor.flat_quad(Vec3::new(-0.5 * w, 0.0, 0.5 * w), Vec3::X * w, Vec3::NEG_Z * (0.8 * w));

    let stripes = [(0.70, 0.12, 0.10), (0.95, 0.75, 0.20), (0.10, 0.35, 0.70), (0.15, 0.55, 0.25)];
    let mut materials: Vec<Material> = stripes
        .iter()
        .enumerate()
        .map(|(i, &(r, g, b))| Material::diffuse(&format!("blinds/wall{i}"), Vec3::new(r, g, b)))
        .collect();
    materials.push(Material::diffuse("blinds/floor", Vec3::splat(0.4)));
    materials.push(Material {
        specular: Vec3::splat(0.35),
        shininess: 60.0,
        ..Material::diffuse("blinds/slat_top", Vec3::splat(0.8))
    });
    materials.push(Material::diffuse("blinds/slat_under", Vec3::new(0.30, 0.08, 0.06)));

    let mut meshes: Vec<_> = wall
        .into_iter()
        .enumerate()
        .map(|(i, b)| b.finish(&format!("blinds/wall{i}"), i))
        .collect();
    meshes.push(floor.finish("blinds/floor", 4));
    meshes.push(tops.finish("blinds/slat_tops", 5));
    meshes.push(rest.finish("blinds/slats", 6));
    Ok(Scene {
        name: "blinds".into(),
        meshes,
        materials,
        camera: Some(Camera::look_at(
            Vec3::new(0.35 * w, 0.3 * w, 1.5 * w),
            Vec3::new(0.0, 0.45 * w, 0.0),
            Vec3::Y,
            40.0,
        )),
        lights: vec![Light::Directional {
            to_light: Vec3::new(-0.3, 0.7, 0.65).normalize(),
            irradiance: Vec3::splat(3.0),
        }],
        background: Vec3::new(0.10, 0.10, 0.12),
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::super::testutil::{check_closed, scene_hash, signed_volume};
    use super::*;
    use crate::Mesh;
    use glam::DVec3;

    /// Möller–Trumbore in f64: whether the ray `o + t·d`, t > 0, hits triangle `tri`.
    fn hits(o: DVec3, d: DVec3, tri: [Vec3; 3]) -> bool {
        let [a, b, c] = tri.map(|p| p.as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-18 {
            return false;
        }
        let s = (o - a) / det;
        let u = s.dot(p);
        let q = s.cross(e1);
        let v = d.dot(q);
        u >= 0.0 && v >= 0.0 && u + v <= 1.0 && e2.dot(q) > 0.0
    }

    /// Fraction of `n` parallel rays along `d`, aimed at heights spread over 40 spacings in the
    /// middle of the panel, that hit a slat.
    fn blocked(slats: &[&Mesh], d: DVec3, p: &BlindsParams, n: usize) -> f64 {
        let g = p.slat_geometry();
        let (lo, span) = (g.bottom as f64 + 20.0 * g.spacing as f64, 40.0 * g.spacing as f64);
        let hit = (0..n)
            .filter(|&i| {
                // A golden-ratio sequence: evenly spread, incommensurate with the spacing.
                let u = (0.5 + i as f64 * 0.618_033_988_749_895).fract();
                let target = DVec3::new(0.0, lo + span * u, 0.0);
                let o = target - d * p.extent as f64;
                slats.iter().any(|m| (0..m.triangle_count()).any(|t| hits(o, d, m.triangle(t))))
            })
            .count();
        hit as f64 / n as f64
    }

    #[test]
    fn opacity_depends_on_direction_as_the_formula_says() {
        let p = BlindsParams { tilt_deg: 45.0, ..Default::default() };
        let s = blinds(&p).unwrap();
        let slats: Vec<&Mesh> = s.meshes.iter().filter(|m| m.name.contains("slat")).collect();
        let g = p.slat_geometry();
        let (sin, cos) = sin_cos_deg(p.tilt_deg);
        let (sin, cos) = (sin as f64, cos as f64);
        let (c, t, sp) = (g.chord as f64, g.thickness as f64, g.spacing as f64);
        // From the front (along −z).
        let front = blocked(&slats, DVec3::NEG_Z, &p, 400);
        let expected = ((c * sin + t * cos) / sp).min(1.0);
        assert!((front - expected).abs() < 0.03, "front {front} vs {expected}");
        // Along the chord, from above-behind toward the front edge: mostly see-through.
        let along = DVec3::new(0.0, -sin, cos).normalize();
        let edge_on = blocked(&slats, -along, &p, 400);
        let expected = t / (sp * cos);
        assert!((edge_on - expected).abs() < 0.03, "edge-on {edge_on} vs {expected}");
        // Across (along the top normal): fully blocked.
        let across = blocked(&slats, DVec3::new(0.0, -cos, -sin), &p, 400);
        assert_eq!(across, 1.0);
        assert!(front > 2.0 * edge_on + 0.4);
    }

    #[test]
    fn slats_are_closed_two_coloured_boxes() {
        let p = BlindsParams { slats: 6, tilt_deg: 30.0, ..Default::default() };
        let s = blinds(&p).unwrap();
        s.validate().unwrap();
        assert_eq!(s.triangle_count(), 12 * 6 + 18);
        let (tops, rest) = (&s.meshes[5], &s.meshes[6]);
        let mut merged = rest.clone();
        let base = merged.positions.len() as u32;
        merged.positions.extend(&tops.positions);
        merged.normals.extend(&tops.normals);
        merged.indices.extend(tops.indices.iter().map(|t| t.map(|i| i + base)));
        check_closed(&merged).unwrap();
        let g = p.slat_geometry();
        let v = 6.0 * (0.9 * p.extent * g.thickness * g.chord) as f64;
        assert!((signed_volume(&merged) / v - 1.0).abs() < 1e-3);
        // The top faces lean toward the camera at positive tilt and are the specular ones.
        assert!(tops.normals.iter().all(|n| n.z > 0.4 && n.y > 0.8));
        assert!(s.materials[tops.material].is_specular());
        assert_eq!(scene_hash(&s), scene_hash(&blinds(&p).unwrap()));
        let e = blinds(&BlindsParams { tilt_deg: 90.0, ..p }).unwrap_err().to_string();
        assert!(e.contains("blinds.tilt") && e.contains("[-89, 89]"), "{e}");
    }
}
