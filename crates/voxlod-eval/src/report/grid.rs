//! Images side by side: an [`ImageGrid`] composes labelled images into one 8-bit sRGB image,
//! row by row, each label drawn under its image with a built-in bitmap font (5×7 capitals:
//! ASCII letters, digits and punctuation; other characters print as `?`), so that a report
//! shows "ground truth | voxels | error" at a glance in any image viewer.

use voxlod_scene::Srgb8Image;

use super::font;
use crate::{Error, Result};

/// The largest composed grid, in pixels (about 64 M; 192 MiB of RGB).
pub const MAX_GRID_PIXELS: u64 = 1 << 26;

/// An image with the label drawn under it.
#[derive(Clone, Debug, PartialEq)]
pub struct LabeledImage {
    /// The label, drawn in 5×7 capitals (characters outside ASCII print as `?`).
    pub label: String,
    /// The image.
    pub image: Srgb8Image,
}

impl LabeledImage {
    /// An image with a label.
    pub fn new(label: impl Into<String>, image: Srgb8Image) -> Self {
        Self { label: label.into(), image }
    }
}

/// Images laid out left to right, `columns` per row. Cells are as large as the largest image;
/// smaller images are centred in theirs. When a label is wider than a cell, all labels are drawn
/// at the largest smaller scale at which they fit (down to 1); labels that still do not fit are
/// cut and end with `.`.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageGrid {
    /// Images per row (at least 1).
    pub columns: u32,
    /// The images, in reading order.
    pub images: Vec<LabeledImage>,
    /// Font pixels per label pixel (1 = 7-pixel-high capitals); 0 draws no labels.
    pub label_scale: u32,
    /// Gap between and around cells, in pixels.
    pub padding: u32,
    /// Background colour.
    pub background: [u8; 3],
    /// Label colour.
    pub label_colour: [u8; 3],
}

impl ImageGrid {
    /// A grid of `images`, `columns` per row, with labels at scale 2 on a white background.
    pub fn new(columns: u32, images: Vec<LabeledImage>) -> Self {
        Self {
            columns,
            images,
            label_scale: 2,
            padding: 8,
            background: [255, 255, 255],
            label_colour: [20, 20, 20],
        }
    }

    /// Composes the grid into one image.
    ///
    /// Errors: no images, zero columns, an image whose buffer does not match its size, or a
    /// result larger than [`MAX_GRID_PIXELS`].
    pub fn compose(&self) -> Result<Srgb8Image> {
        if self.images.is_empty() {
            return Err(Error::InvalidGrid { reason: "it has no images" });
        }
        if self.columns == 0 {
            return Err(Error::InvalidGrid { reason: "it has zero columns" });
        }
        for LabeledImage { image, .. } in &self.images {
            if image.pixels.len() as u64 != u64::from(image.width) * u64::from(image.height) {
                return Err(Error::PixelCount {
                    width: image.width,
                    height: image.height,
                    pixels: image.pixels.len(),
                });
            }
        }
        let n = self.images.len() as u64;
        let cols = u64::from(self.columns).min(n);
        let rows = n.div_ceil(cols);
        let cell_w = self.images.iter().map(|i| u64::from(i.image.width)).max().unwrap_or(0);
        let img_h = self.images.iter().map(|i| u64::from(i.image.height)).max().unwrap_or(0);
        let longest = self.images.iter().map(|i| i.label.chars().count()).max().unwrap_or(0);
        let scale = (1..=self.label_scale)
            .rev()
            .find(|&s| u64::from(font::text_width(&"x".repeat(longest), s)) <= cell_w)
            .unwrap_or(self.label_scale.min(1));
        let label_h = u64::from((font::CELL_HEIGHT + 2) * scale);
        let pad = u64::from(self.padding);
        let width = pad + cols * (cell_w + pad);
        let height = pad + rows * (img_h + label_h + pad);
        if width.saturating_mul(height) > MAX_GRID_PIXELS || width > u64::from(u32::MAX) {
            return Err(Error::InvalidGrid { reason: "the composed image would be too large" });
        }
        let mut out = Srgb8Image::new(width as u32, height as u32, self.background);
        for (i, LabeledImage { label, image }) in self.images.iter().enumerate() {
            let (col, row) = (i as u64 % cols, i as u64 / cols);
            let x0 = pad + col * (cell_w + pad);
            let y0 = pad + row * (img_h + label_h + pad);
            let ix = x0 + (cell_w - u64::from(image.width)) / 2;
            let iy = y0 + (img_h - u64::from(image.height)) / 2;
            blit(&mut out, image, ix as usize, iy as usize);
            if scale > 0 {
                let text = fit_label(label, cell_w, scale);
                let tw = u64::from(font::text_width(&text, scale));
                let tx = x0 + cell_w.saturating_sub(tw) / 2;
                let ty = y0 + img_h + u64::from(scale) * 2;
                font::draw_text(&mut out, tx as i64, ty as i64, &text, scale, self.label_colour);
            }
        }
        Ok(out)
    }
}

/// The label, cut to fit `width` pixels (ending in `.` when cut).
fn fit_label(label: &str, width: u64, scale: u32) -> String {
    let chars: Vec<char> = label.chars().collect();
    let fits = |n: usize| u64::from(font::text_width(&"x".repeat(n), scale)) <= width;
    if fits(chars.len()) {
        return label.to_owned();
    }
    let mut n = chars.len();
    while n > 0 && !fits(n) {
        n -= 1;
    }
    let mut cut: String = chars[..n.saturating_sub(1)].iter().collect();
    if n > 0 {
        cut.push('.');
    }
    cut
}

fn blit(dst: &mut Srgb8Image, src: &Srgb8Image, x: usize, y: usize) {
    let (dw, sw) = (dst.width as usize, src.width as usize);
    for (r, row) in src.pixels.chunks_exact(sw.max(1)).enumerate() {
        let start = (y + r) * dw + x;
        dst.pixels[start..start + sw].copy_from_slice(row);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_places_images_and_labels() {
        let red = Srgb8Image::new(20, 6, [255, 0, 0]);
        let blue = Srgb8Image::new(4, 4, [0, 0, 255]);
        let mut grid = ImageGrid::new(
            2,
            vec![
                LabeledImage::new("ref", red.clone()),
                LabeledImage::new("b", blue),
                LabeledImage::new("c", red),
            ],
        );
        grid.label_scale = 1;
        grid.padding = 2;
        let out = grid.compose().unwrap();
        // 2 columns of 20 px, 2 rows of (6 + 10) px, 2 px padding.
        assert_eq!((out.width, out.height), (2 + 2 * 22, 2 + 2 * 18));
        assert_eq!(out.get(2, 2), [255, 0, 0]);
        assert_eq!(out.get(21, 7), [255, 0, 0]);
        // The blue image is centred in its 20×6 cell: x from 24 + 8, y from 2 + 1.
        assert_eq!(out.get(32, 3), [0, 0, 255]);
        assert_eq!(out.get(31, 3), [255, 255, 255]);
        // The label "REF" (17 px wide) is drawn under the first image, centred.
        let strip = (10..17u32).flat_map(|y| (3..20u32).map(move |x| (x, y)));
        let inked = strip.filter(|&(x, y)| out.get(x, y) == [20, 20, 20]).count();
        assert!(inked > 20, "{inked} label pixels");
        assert_eq!(out.get(2, 12), [255, 255, 255]);
        // The last row holds one image; the empty cell stays background.
        assert_eq!(out.get(30, 25), [255, 255, 255]);
        assert_eq!(out.get(2, 20), [255, 0, 0]);
    }

    #[test]
    fn long_labels_are_cut_and_bad_grids_are_errors() {
        assert_eq!(fit_label("short", 100, 1), "short");
        let cut = fit_label("a very long label indeed", 40, 1);
        assert!(cut.ends_with('.') && u64::from(font::text_width(&cut, 1)) <= 40, "{cut}");
        assert_eq!(fit_label("abc", 2, 1), "");
        // "abcd" is 46 px wide at scale 2, 23 px at scale 1: a 30 px cell takes scale 1.
        let mut g =
            ImageGrid::new(1, vec![LabeledImage::new("abcd", Srgb8Image::new(30, 5, [0; 3]))]);
        g.padding = 0;
        assert_eq!(g.compose().unwrap().height, 5 + 10);
        g.label_scale = 0;
        assert_eq!(g.compose().unwrap().height, 5);
        assert!(ImageGrid::new(2, vec![]).compose().is_err());
        let one = vec![LabeledImage::new("x", Srgb8Image::new(2, 2, [0; 3]))];
        assert!(ImageGrid::new(0, one.clone()).compose().is_err());
        let huge = Srgb8Image { width: 1 << 20, height: 1 << 20, pixels: vec![] };
        let err = ImageGrid::new(1, vec![LabeledImage::new("h", huge)]).compose().unwrap_err();
        assert!(matches!(err, Error::PixelCount { .. }), "{err}");
    }
}
