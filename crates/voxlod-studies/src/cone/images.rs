//! The cone study's images: the ray-traced references and the sweep's best AO and indirect
//! rows, as 8-bit sRGB with per-pixel error heat maps and as linear float arrays.

use glam::{Vec3, Vec4};
use voxlod_cpu::render::ground_truth::GBuffer;
use voxlod_eval::error_heatmap;
use voxlod_eval::npy::FloatArray;
use voxlod_eval::report::LabeledImage;
use voxlod_scene::{Image, Srgb8Image};

use crate::Error;

/// One cone-traced image of the sweep, per pixel: AO, and `E/π` (before the albedo).
pub(super) struct Traced {
    pub(super) ao: Vec<f32>,
    pub(super) irradiance: Vec<Vec3>,
}

/// The best row of the sweep for one target so far: its MSE, label and image.
pub(super) struct Best {
    mse: f64,
    pub(super) label: String,
    traced: Traced,
}

impl Best {
    pub(super) fn keep(
        best: &mut Option<Best>,
        mse: f64,
        label: impl Fn() -> String,
        traced: &Traced,
    ) {
        if best.as_ref().is_none_or(|b| mse < b.mse) {
            let traced = Traced { ao: traced.ao.clone(), irradiance: traced.irradiance.clone() };
            *best = Some(Best { mse, label: label(), traced });
        }
    }
}

pub(super) fn gray(gb: &GBuffer, v: &[f32]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for (p, &a) in img.pixels.iter_mut().zip(v) {
        *p = Vec3::splat(a).extend(1.0);
    }
    img.to_srgb8()
}

pub(super) fn colour(gb: &GBuffer, e: &[Vec3]) -> Srgb8Image {
    let mut img = Image::new(gb.width, gb.height, Vec4::ZERO);
    for ((p, &e), t) in img.pixels.iter_mut().zip(e).zip(&gb.texels) {
        *p = (t.albedo * e).extend(1.0);
    }
    img.to_srgb8()
}

/// The references, the best AO row's and the best indirect row's images with their per-pixel
/// error heat maps (8-bit sRGB), and the same in linear float: AO as `[height, width]`,
/// `albedo · E/π` as `[height, width, 3]`.
pub(super) fn reference_outputs(
    gb: &GBuffer,
    ao_ref: &[f32],
    ind_ref: &[Vec3],
    best_ao: Option<Best>,
    best_indirect: Option<Best>,
) -> Result<(Vec<LabeledImage>, Vec<FloatArray>), Error> {
    let (w, h) = (gb.width as usize, gb.height as usize);
    let outgoing = |e: &[Vec3]| -> Vec<f32> {
        e.iter().zip(&gb.texels).flat_map(|(e, t)| (t.albedo * *e).to_array()).collect()
    };
    let gray_array = |name: &str, v: &[f32]| FloatArray {
        name: name.into(),
        shape: vec![h, w],
        data: v.to_vec(),
    };
    let rgb_array = |name: &str, e: &[Vec3]| FloatArray {
        name: name.into(),
        shape: vec![h, w, 3],
        data: outgoing(e),
    };
    let (ao_img, ind_img) = (gray(gb, ao_ref), colour(gb, ind_ref));
    // Labels stay short (they are drawn inside images as small as 16 px); the caption names
    // the rows.
    let mut images = vec![LabeledImage::new("AO ref", ao_img.clone())];
    let mut arrays = vec![gray_array("ao_reference", ao_ref)];
    if let Some(b) = best_ao {
        let img = gray(gb, &b.traced.ao);
        images.push(LabeledImage::new("AO best", img.clone()));
        images.push(LabeledImage::new("AO err", error_heatmap(&img, &ao_img, 0.25)?));
        arrays.push(gray_array("ao_best", &b.traced.ao));
    }
    images.push(LabeledImage::new("ind ref", ind_img.clone()));
    arrays.push(rgb_array("indirect_reference", ind_ref));
    if let Some(b) = best_indirect {
        let img = colour(gb, &b.traced.irradiance);
        images.push(LabeledImage::new("ind best", img.clone()));
        images.push(LabeledImage::new("ind err", error_heatmap(&img, &ind_img, 0.25)?));
        arrays.push(rgb_array("indirect_best", &b.traced.irradiance));
    }
    Ok((images, arrays))
}
