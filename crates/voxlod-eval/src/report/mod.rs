//! Experiment reports, generated, never typed: a [`Report`] collects [`Section`]s — headings,
//! markdown text, [`Table`]s, [`ImageGrid`]s, [`Plot`]s, [`Animation`]s — and [`Report::write`]
//! puts `report.md`, `report.json` (every table, plot, image grid and animation, numbers at full
//! precision) and `assets/` (SVG plots, PNG grids and full-size PNGs, animated PNGs) into a
//! directory, each file atomically.
//!
//! ```no_run
//! use voxlod_eval::report::{Column, NumberFormat, Plot, Report, Series, Table};
//! let mut table = Table::new("baseline", vec![
//!     Column::text("resolution"),
//!     Column::number("MSE", NumberFormat::Scientific(2)),
//!     Column::number("time (ms)", NumberFormat::Fixed(1)),
//! ]);
//! table.push_row(vec!["64³".into(), 0.0123.into(), 12.5.into()])?;
//! let plot = Plot {
//!     title: "error against cost".into(),
//!     x_label: "time (ms)".into(),
//!     y_label: "MSE".into(),
//!     log_x: true,
//!     series: vec![Series::new("averages", vec![(12.5, 0.0123), (80.0, 0.004)])],
//!     ..Plot::default()
//! };
//! let mut report = Report::new("Voxel baseline");
//! report.heading(2, "Forest").text("Three viewpoints.").table(table).plot("forest-plot", plot);
//! report.write(std::path::Path::new("out"))?;
//! # Ok::<(), voxlod_eval::Error>(())
//! ```

mod font;
mod grid;
mod plot;
mod summary;
mod table;

use std::collections::HashSet;
use std::path::{Path, PathBuf};

pub use grid::{ImageGrid, LabeledImage, MAX_GRID_PIXELS};
pub use plot::{PLOTTABLE_LIMIT, Plot, RenderedPlot, Series, SeriesStyle, SkippedPoint};
pub use summary::{
    AnimationSummary, ImagesSummary, PlotSummary, SeriesSummary, Summary, TableSummary,
};
pub use table::{Align, Cell, Column, NumberFormat, Table, format_number};

use crate::animation::Animation;
use crate::{Error, Result};

/// One part of a report, in order. More kinds will be added: match with a wildcard arm.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Section {
    /// A heading; `level` 2–6 (the report's title is the only level-1 heading).
    Heading {
        /// Markdown heading level, clamped to 2..=6.
        level: u8,
        /// The heading's text (one line).
        text: String,
    },
    /// A paragraph of markdown, written as given.
    Text(String),
    /// A table, rendered in markdown and kept in full in the JSON summary.
    Table(Table),
    /// Images side by side: written as `assets/<name>.png` (the labelled grid) and
    /// `assets/<name>/<i>.png` (each image at full size, `i` from 0).
    Images {
        /// Asset name: letters, digits, `-`, `_`; unique within the report.
        name: String,
        /// Caption under the grid.
        caption: String,
        /// The images.
        grid: ImageGrid,
    },
    /// Linear float arrays (e.g. the values behind images), written as
    /// `assets/<name>/<array name>.npy` and linked under `caption`.
    Data {
        /// Asset name: letters, digits, `-`, `_`; unique within the report.
        name: String,
        /// What the arrays hold.
        caption: String,
        /// The arrays (names unique within the section).
        arrays: Vec<crate::npy::FloatArray>,
    },
    /// A plot, written as `assets/<name>.svg`; points it could not draw are listed under it.
    Plot {
        /// Asset name: letters, digits, `-`, `_`; unique within the report.
        name: String,
        /// The plot.
        plot: Plot,
    },
    /// An animation, written as the animated PNG `assets/<name>.png` and shown in place (viewers
    /// without APNG support show its first frame).
    Animation {
        /// Asset name: letters, digits, `-`, `_`; unique within the report.
        name: String,
        /// Caption under it.
        caption: String,
        /// The frames.
        animation: Animation,
    },
}

/// A report under construction. Sections appear in the order they are added.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// The title (the level-1 heading).
    pub title: String,
    /// The sections, in order.
    pub sections: Vec<Section>,
}

/// The files a [`Report::write`] produced.
#[derive(Clone, Debug, PartialEq)]
pub struct WrittenReport {
    /// `report.md`.
    pub markdown: PathBuf,
    /// `report.json`.
    pub summary: PathBuf,
    /// Everything under `assets/`, in the order written.
    pub assets: Vec<PathBuf>,
    /// Plot points that could not be drawn (also noted in the markdown and the JSON).
    pub skipped_points: Vec<SkippedPoint>,
}

impl Report {
    /// An empty report.
    pub fn new(title: impl Into<String>) -> Self {
        Self { title: title.into(), sections: Vec::new() }
    }

    /// Appends a section.
    pub fn push(&mut self, section: Section) -> &mut Self {
        self.sections.push(section);
        self
    }

    /// Appends a heading of `level` (clamped to 2..=6).
    pub fn heading(&mut self, level: u8, text: impl Into<String>) -> &mut Self {
        self.push(Section::Heading { level, text: text.into() })
    }

    /// Appends a paragraph of markdown.
    pub fn text(&mut self, markdown: impl Into<String>) -> &mut Self {
        self.push(Section::Text(markdown.into()))
    }

    /// Appends a table.
    pub fn table(&mut self, table: Table) -> &mut Self {
        self.push(Section::Table(table))
    }

    /// Appends images side by side.
    pub fn images(
        &mut self,
        name: impl Into<String>,
        caption: impl Into<String>,
        grid: ImageGrid,
    ) -> &mut Self {
        self.push(Section::Images { name: name.into(), caption: caption.into(), grid })
    }

    /// Appends linear float arrays, written as `.npy` files (see [`Section::Data`]).
    pub fn data(
        &mut self,
        name: impl Into<String>,
        caption: impl Into<String>,
        arrays: Vec<crate::npy::FloatArray>,
    ) -> &mut Self {
        self.push(Section::Data { name: name.into(), caption: caption.into(), arrays })
    }

    /// Appends a plot.
    pub fn plot(&mut self, name: impl Into<String>, plot: Plot) -> &mut Self {
        self.push(Section::Plot { name: name.into(), plot })
    }

    /// Appends an animation (see [`Section::Animation`]).
    pub fn animation(
        &mut self,
        name: impl Into<String>,
        caption: impl Into<String>,
        animation: Animation,
    ) -> &mut Self {
        self.push(Section::Animation { name: name.into(), caption: caption.into(), animation })
    }

    /// Writes `report.md`, `report.json` and `assets/` into `dir` (created if missing). Every
    /// file is written atomically; assets first and `report.md` last, so a report never links
    /// to an asset that was not written. Fails before writing anything if an asset name is
    /// invalid or repeated, a grid cannot be composed, a plot cannot be drawn or an animation
    /// cannot be encoded.
    pub fn write(&self, dir: &Path) -> Result<WrittenReport> {
        self.check_names()?;
        let mut files: Vec<(String, Vec<u8>)> = Vec::new();
        let mut skipped_points = Vec::new();
        let mut summary = Summary::new(&self.title);
        let mut md = format!("# {}\n", one_line(&self.title));
        let mut heading = String::new();
        for section in &self.sections {
            md.push('\n');
            match section {
                Section::Heading { level, text } => {
                    heading = one_line(text);
                    md += &format!("{} {heading}\n", "#".repeat((*level).clamp(2, 6).into()));
                }
                Section::Text(text) => md += &format!("{}\n", text.trim_end()),
                Section::Table(table) => {
                    md += &table.to_markdown();
                    summary.add_table(&heading, table);
                }
                Section::Images { name, caption, grid } => {
                    let png = grid.compose()?;
                    files.push((format!("{name}.png"), encode(&png, name)?));
                    let mut links = Vec::new();
                    for (i, img) in grid.images.iter().enumerate() {
                        let file = format!("{name}/{i}.png");
                        links.push(format!("[{}](assets/{file})", one_line(&img.label)));
                        files.push((file, encode(&img.image, name)?));
                    }
                    md += &format!(
                        "![{0}](assets/{name}.png)\n\n*{0}* — full size: {1}\n",
                        one_line(caption),
                        links.join(" · ")
                    );
                    summary.add_images(&heading, name, caption, grid);
                }
                Section::Data { name, caption, arrays } => {
                    let mut links = Vec::new();
                    for a in arrays {
                        let file = format!("{name}/{}.npy", a.name);
                        links.push(format!("[{}](assets/{file})", a.name));
                        files.push((file, crate::npy::encode_f32(&a.shape, &a.data)?));
                    }
                    md += &format!(
                        "*{}* — linear float32 arrays (`numpy.load`): {}\n",
                        one_line(caption),
                        links.join(" · ")
                    );
                }
                Section::Plot { name, plot } => {
                    let rendered = plot.render_svg()?;
                    files.push((format!("{name}.svg"), rendered.svg.into_bytes()));
                    md += &format!("![{}](assets/{name}.svg)\n", one_line(&plot.title));
                    if !rendered.skipped.is_empty() {
                        md += &skipped_note(&rendered.skipped);
                    }
                    summary.add_plot(&heading, name, plot, &rendered.skipped);
                    skipped_points.extend(rendered.skipped);
                }
                Section::Animation { name, caption, animation } => {
                    files.push((format!("{name}.png"), crate::animation::encode_apng(animation)?));
                    let (w, h) = animation.size();
                    md += &format!(
                        "![{0}](assets/{name}.png)\n\n*{0}* — animated PNG: {1} frames of {w}×{h}, \
                         {2} ms each, looping.\n",
                        one_line(caption),
                        animation.frames.len(),
                        animation.frame_ms
                    );
                    summary.add_animation(&heading, name, caption, animation);
                }
            }
        }
        let write = |path: PathBuf, bytes: &[u8]| -> Result<PathBuf> {
            voxlod_format::io::write_bytes_atomic(&path, bytes)
                .map_err(|source| Error::Write { path: path.clone(), source })?;
            Ok(path)
        };
        let mut assets = Vec::with_capacity(files.len());
        for (file, bytes) in &files {
            assets.push(write(dir.join("assets").join(file), bytes)?);
        }
        let json = serde_json::to_vec_pretty(&summary)
            .map_err(|source| Error::Json { what: "the report summary", source })?;
        let summary = write(dir.join("report.json"), &json)?;
        let markdown = write(dir.join("report.md"), md.as_bytes())?;
        Ok(WrittenReport { markdown, summary, assets, skipped_points })
    }

    fn check_names(&self) -> Result<()> {
        let check = |name: &String| {
            let valid = !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if valid { Ok(()) } else { Err(Error::InvalidAssetName { name: name.clone() }) }
        };
        let mut seen = HashSet::new();
        for section in &self.sections {
            let name = match section {
                Section::Images { name, .. }
                | Section::Plot { name, .. }
                | Section::Animation { name, .. } => name,
                Section::Data { name, arrays, .. } => {
                    let mut files = HashSet::new();
                    for a in arrays {
                        check(&a.name)?;
                        if !files.insert(a.name.to_ascii_lowercase()) {
                            return Err(Error::DuplicateAsset {
                                name: format!("{name}/{}", a.name),
                            });
                        }
                    }
                    name
                }
                _ => continue,
            };
            check(name)?;
            // Case-insensitively: some file systems would write both to one file.
            if !seen.insert(name.to_ascii_lowercase()) {
                return Err(Error::DuplicateAsset { name: name.clone() });
            }
        }
        Ok(())
    }
}

fn encode(img: &voxlod_scene::Srgb8Image, name: &str) -> Result<Vec<u8>> {
    img.encode_png().map_err(|source| Error::Encode { what: format!("image '{name}'"), source })
}

fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

fn skipped_note(skipped: &[SkippedPoint]) -> String {
    let list: Vec<String> = skipped
        .iter()
        .map(|p| {
            format!("'{}' #{} ({}, {}): {}", p.series, p.index, p.point.0, p.point.1, p.reason)
        })
        .collect();
    format!("\n> Note: {} point(s) not drawn: {}.\n", skipped.len(), list.join("; "))
}

#[cfg(test)]
mod tests;
