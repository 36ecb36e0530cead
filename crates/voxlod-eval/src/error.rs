//! The error type of voxlod-eval: what can go wrong scoring images and writing reports. Each
//! variant names what and where.

use std::path::PathBuf;

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in voxlod-eval.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Two images that are compared pixel by pixel differ in size.
    #[error(
        "cannot compare images of different sizes: {a_width}×{a_height} and {b_width}×{b_height}"
    )]
    SizeMismatch {
        /// Width of the first image.
        a_width: u32,
        /// Height of the first image.
        a_height: u32,
        /// Width of the second image.
        b_width: u32,
        /// Height of the second image.
        b_height: u32,
    },
    /// An image is smaller than a metric needs.
    #[error(
        "{metric} needs images of at least {min}×{min} pixels, got {width}×{height}{hint}",
        hint = if *metric == "SSIM" {
            " (the 11×11 Gaussian window of Wang et al. 2004, as scikit-image requires)"
        } else {
            ""
        }
    )]
    ImageTooSmall {
        /// The metric ("MSE", "SSIM", ...).
        metric: &'static str,
        /// Width of the image.
        width: u32,
        /// Height of the image.
        height: u32,
        /// The smallest side length the metric accepts.
        min: u32,
    },
    /// An image's pixel buffer does not hold `width × height` pixels.
    #[error("image of {width}×{height} pixels holds {pixels} pixels in its buffer")]
    PixelCount {
        /// Declared width.
        width: u32,
        /// Declared height.
        height: u32,
        /// Length of the pixel buffer.
        pixels: usize,
    },
    /// A numeric parameter is out of its domain.
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A table row has the wrong number of cells.
    #[error("table '{table}': row {row} has {got} cells, the table has {expected} columns")]
    RowLength {
        /// The table's name.
        table: String,
        /// Index of the offending row.
        row: usize,
        /// Number of columns.
        expected: usize,
        /// Number of cells given.
        got: usize,
    },
    /// An array's shape does not hold its values.
    #[error("an array of shape {shape:?} holds {values} values")]
    ArrayShape {
        /// The shape given.
        shape: Vec<usize>,
        /// The number of values.
        values: usize,
    },
    /// Bytes that are not the `.npy` layout this crate writes.
    #[error("not a readable .npy array: {why}")]
    Npy {
        /// What is wrong.
        why: String,
    },
    /// A report asset name is empty or holds characters other than `[A-Za-z0-9_-]`.
    #[error("invalid asset name '{name}': use letters, digits, '-' and '_' only")]
    InvalidAssetName {
        /// The name given.
        name: String,
    },
    /// Two report sections would write the same asset file.
    #[error("two report sections are both named '{name}'")]
    DuplicateAsset {
        /// The repeated name.
        name: String,
    },
    /// An image grid that cannot be composed: no images, no columns, or too large.
    #[error("image grid: {reason}")]
    InvalidGrid {
        /// What is wrong.
        reason: &'static str,
    },
    /// Drawing a plot failed inside plotters.
    #[error("plot '{title}': {reason}")]
    Plot {
        /// The plot's title.
        title: String,
        /// The drawing backend's message.
        reason: String,
    },
    /// Encoding an image as PNG failed.
    #[error("encoding {what}: {source}")]
    Encode {
        /// Which image.
        what: String,
        /// The underlying error.
        #[source]
        source: voxlod_scene::Error,
    },
    /// An animation that cannot be encoded or decoded (an APNG error, frames it cannot read).
    #[error("animated PNG: {reason}")]
    Animation {
        /// What went wrong.
        reason: String,
    },
    /// Serializing the JSON summary failed.
    #[error("serializing {what} as JSON: {source}")]
    Json {
        /// What was being serialized.
        what: &'static str,
        /// The underlying error.
        #[source]
        source: serde_json::Error,
    },
    /// Writing a file failed (the old file, if any, is left untouched).
    #[error("writing {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: voxlod_format::Error,
    },
}
