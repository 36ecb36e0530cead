//! Ground truths cached on disk by their inputs: a 1024-rays-per-pixel render of a dense scene is
//! the most expensive image of the paper setup, and every variant that does not change the
//! scene, camera, lights, background or image side scores against the same one.
//!
//! An entry is the linear RGBA image as a `.npy` array of shape `[height, width, 4]` (f32), named
//! by a 64-bit FNV-1a hash of its key, with the full key beside it (`.key`): a load checks the
//! key, so a hash collision reads as a miss, never as a wrong image. The key holds the scene
//! spec, a fingerprint of its triangles and materials, the camera, every light, the background,
//! the ambient term, the image side, the rays per pixel, the seed and
//! [`GROUND_TRUTH_VERSION`]. Entries are written atomically.

use std::path::{Path, PathBuf};

use glam::Vec4;
use voxlod_scene::{Camera, Image, Light, Scene};

use crate::Error;

/// Bumped whenever the ground-truth renderer's output changes, so old entries miss.
pub const GROUND_TRUTH_VERSION: u32 = 1;

/// A directory of cached ground truths (None: no cache, every image is rendered).
#[derive(Clone, Debug, Default)]
pub struct TruthCache {
    dir: Option<PathBuf>,
    hits: std::cell::Cell<usize>,
    misses: std::cell::Cell<usize>,
}

impl TruthCache {
    /// A cache in `dir` (created on the first store), or none.
    pub fn new(dir: Option<PathBuf>) -> Self {
        Self { dir, ..Self::default() }
    }

    /// The directory, if any.
    pub fn dir(&self) -> Option<&Path> {
        self.dir.as_deref()
    }

    /// Images loaded from the cache and rendered (missed) so far.
    pub fn counts(&self) -> (usize, usize) {
        (self.hits.get(), self.misses.get())
    }

    /// The cached image for `key`, or `render()`'s, which is then stored.
    pub fn get_or_render(
        &self,
        key: &str,
        render: impl FnOnce() -> Result<Image, Error>,
    ) -> Result<Image, Error> {
        let Some(dir) = &self.dir else {
            self.misses.set(self.misses.get() + 1);
            return render();
        };
        let stem = dir.join(format!("{:016x}", fnv1a(key.as_bytes())));
        let (npy, key_file) = (stem.with_extension("npy"), stem.with_extension("key"));
        if let Some(image) = load(&npy, &key_file, key) {
            self.hits.set(self.hits.get() + 1);
            return Ok(image);
        }
        self.misses.set(self.misses.get() + 1);
        let image = render()?;
        std::fs::create_dir_all(dir).map_err(|e| voxlod_format::Error::Io {
            op: "creating",
            path: dir.clone(),
            source: e,
        })?;
        let data: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
        let shape = [image.height as usize, image.width as usize, 4];
        let bytes = voxlod_eval::npy::encode_f32(&shape, &data)?;
        // The image first: a key without its image is a miss, an image without its key too.
        voxlod_format::io::write_bytes_atomic(&npy, &bytes)?;
        voxlod_format::io::write_bytes_atomic(&key_file, key.as_bytes())?;
        Ok(image)
    }
}

/// Reads an entry whose key file matches `key` exactly; anything else (absent, other key,
/// unreadable, wrong shape) is a miss.
fn load(npy: &Path, key_file: &Path, key: &str) -> Option<Image> {
    if std::fs::read(key_file).ok()? != key.as_bytes() {
        return None;
    }
    let (shape, data) = voxlod_eval::npy::decode_f32(&std::fs::read(npy).ok()?).ok()?;
    let [h, w, 4] = shape[..] else { return None };
    if data.len() != h * w * 4 {
        return None;
    }
    let pixels = data.chunks_exact(4).map(Vec4::from_slice).collect();
    Some(Image { width: u32::try_from(w).ok()?, height: u32::try_from(h).ok()?, pixels })
}

/// Every input that changes a ground truth's pixels.
#[derive(Clone, Copy, Debug)]
pub struct TruthInputs<'a> {
    /// The scene spec it was loaded from.
    pub spec: &'a str,
    /// The scene (its triangles, materials and background are fingerprinted).
    pub scene: &'a Scene,
    /// The camera.
    pub camera: &'a Camera,
    /// Every light.
    pub lights: &'a [Light],
    /// The ambient term.
    pub ambient: glam::Vec3,
    /// Image side.
    pub size: u32,
    /// Rays per pixel.
    pub spp: u32,
    /// Seed.
    pub seed: u32,
}

impl TruthInputs<'_> {
    /// The cache key: every input, in text.
    pub fn key(&self) -> String {
        format!(
            "voxlod ground truth v{GROUND_TRUTH_VERSION} (voxlod {})\nscene {}\ngeometry {:016x}\n\
             camera {:?}\nlights {:?}\nbackground {:?}\nambient {:?}\nsize {}\nspp {}\nseed {}\n",
            env!("CARGO_PKG_VERSION"),
            self.spec,
            scene_fingerprint(self.scene),
            self.camera,
            self.lights,
            self.scene.background,
            self.ambient,
            self.size,
            self.spp,
            self.seed,
        )
    }
}

/// FNV-1a over every mesh's positions, normals, UVs, indices and material, and every material's
/// parameters (textures by size and texels).
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    for m in &scene.meshes {
        for p in &m.positions {
            h.floats(&p.to_array());
        }
        for n in &m.normals {
            h.floats(&n.to_array());
        }
        for uv in &m.uvs {
            h.floats(&uv.to_array());
        }
        for t in &m.indices {
            for i in t {
                h.bytes(&i.to_le_bytes());
            }
        }
        h.bytes(&(m.material as u64).to_le_bytes());
    }
    for m in &scene.materials {
        h.bytes(format!("{m:?}").as_bytes());
    }
    for t in &scene.textures {
        h.bytes(&t.width.to_le_bytes());
        h.bytes(&t.height.to_le_bytes());
        for texel in t.texels.iter() {
            h.bytes(texel);
        }
    }
    h.0
}

struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn floats(&mut self, f: &[f32]) {
        for x in f {
            self.bytes(&x.to_bits().to_le_bytes());
        }
    }
}

fn fnv1a(b: &[u8]) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.bytes(b);
    h.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(v: f32) -> Image {
        Image::new(3, 2, Vec4::new(v, 0.5, 0.25, 1.0))
    }

    #[test]
    fn a_stored_image_is_loaded_back_and_another_key_misses() {
        let dir = std::env::temp_dir().join(format!("voxlod-truth-cache-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cache = TruthCache::new(Some(dir.clone()));
        let first = cache.get_or_render("key a", || Ok(image(0.125))).unwrap();
        let again = cache.get_or_render("key a", || panic!("must not render again")).unwrap();
        assert_eq!(first, again);
        let other = cache.get_or_render("key b", || Ok(image(0.75))).unwrap();
        assert_eq!(other, image(0.75));
        assert_eq!(cache.counts(), (1, 2));
        // A key file that does not match (a collision, a truncated write) is a miss.
        let stem = dir.join(format!("{:016x}", fnv1a(b"key a")));
        std::fs::write(stem.with_extension("key"), "something else").unwrap();
        let rendered = cache.get_or_render("key a", || Ok(image(0.5))).unwrap();
        assert_eq!(rendered, image(0.5));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_key_changes_with_every_input() {
        let scene = voxlod_scene::procedural::builtin("sphere", &[("subdiv", "1")]).unwrap();
        let camera = scene.default_camera().unwrap();
        let lights = [scene.light()];
        let key = |spec, scene, camera, lights, ambient, size, spp, seed| {
            TruthInputs { spec, scene, camera, lights, ambient, size, spp, seed }.key()
        };
        let base = key("s", &scene, &camera, &lights, glam::Vec3::ZERO, 8, 4, 0);
        let moved = Camera { eye: camera.eye + glam::Vec3::X, ..camera };
        let mut white = scene.clone();
        white.background = glam::Vec3::ONE;
        let mut bumped = scene.clone();
        bumped.meshes[0].positions[0].x += 1e-6;
        for other in [
            key("t", &scene, &camera, &lights, glam::Vec3::ZERO, 8, 4, 0),
            key("s", &scene, &moved, &lights, glam::Vec3::ZERO, 8, 4, 0),
            key("s", &scene, &camera, &[], glam::Vec3::ZERO, 8, 4, 0),
            key("s", &white, &camera, &lights, glam::Vec3::ZERO, 8, 4, 0),
            key("s", &bumped, &camera, &lights, glam::Vec3::ZERO, 8, 4, 0),
            key("s", &scene, &camera, &lights, glam::Vec3::ONE, 8, 4, 0),
            key("s", &scene, &camera, &lights, glam::Vec3::ZERO, 9, 4, 0),
            key("s", &scene, &camera, &lights, glam::Vec3::ZERO, 8, 5, 0),
            key("s", &scene, &camera, &lights, glam::Vec3::ZERO, 8, 4, 1),
        ] {
            assert_ne!(base, other);
        }
    }
}
