//! The machine-readable side of a report: `report.json`, a [`Summary`] of every table (all
//! cells at full precision), every plot (its series and the points it skipped) and every image
//! grid (its files), each tagged with the heading it appeared under. Numbers that are not finite
//! are written as the strings `"inf"`, `"-inf"`, `"nan"` (see [`crate::json`]).

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::{ImageGrid, Plot, SkippedPoint, Table};
use crate::animation::Animation;
use crate::json;

/// The JSON summary of a report (`report.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The report's title.
    pub title: String,
    /// Every table, in report order.
    pub tables: Vec<TableSummary>,
    /// Every plot, in report order.
    pub plots: Vec<PlotSummary>,
    /// Every image grid, in report order.
    pub images: Vec<ImagesSummary>,
    /// Every animation, in report order.
    #[serde(default)]
    pub animations: Vec<AnimationSummary>,
}

/// An animation in the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnimationSummary {
    /// The asset name.
    pub name: String,
    /// The heading it appeared under.
    pub section: String,
    /// The caption.
    pub caption: String,
    /// The animated PNG, relative to the report directory.
    pub file: String,
    /// Number of frames.
    pub frames: usize,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// How long each frame shows, in milliseconds.
    pub frame_ms: u16,
}

/// A table in the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableSummary {
    /// The table's name.
    pub name: String,
    /// The heading it appeared under ("" before the first heading).
    pub section: String,
    /// Column headers.
    pub columns: Vec<String>,
    /// Rows of cells: a number, a string (text, or `"inf"`/`"-inf"`/`"nan"`), or `null`.
    pub rows: Vec<Vec<Value>>,
}

/// A plot in the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlotSummary {
    /// The asset name (`assets/<name>.svg`).
    pub name: String,
    /// The heading it appeared under.
    pub section: String,
    /// The plot's title.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// Log-scale x axis.
    pub log_x: bool,
    /// Log-scale y axis.
    pub log_y: bool,
    /// Each series' name and all its points, drawn or not.
    pub series: Vec<SeriesSummary>,
    /// The points that were not drawn, as `{series, index, point, reason}`.
    pub skipped: Vec<Value>,
}

/// One series of a plot in the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SeriesSummary {
    /// The series' name.
    pub name: String,
    /// Its points as `[x, y]`.
    pub points: Vec<[Value; 2]>,
}

/// An image grid in the summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImagesSummary {
    /// The asset name.
    pub name: String,
    /// The heading it appeared under.
    pub section: String,
    /// The caption.
    pub caption: String,
    /// The composed grid, relative to the report directory.
    pub file: String,
    /// Each image: `{label, file, width, height}`.
    pub images: Vec<Value>,
}

impl Summary {
    /// An empty summary.
    pub(crate) fn new(title: &str) -> Self {
        Self {
            title: title.to_owned(),
            tables: vec![],
            plots: vec![],
            images: vec![],
            animations: vec![],
        }
    }

    pub(crate) fn add_table(&mut self, section: &str, table: &Table) {
        let cell = |c| serde_json::to_value(c).unwrap_or(Value::Null);
        self.tables.push(TableSummary {
            name: table.name().to_owned(),
            section: section.to_owned(),
            columns: table.columns().iter().map(|c| c.name.clone()).collect(),
            rows: table.rows().iter().map(|r| r.iter().map(cell).collect()).collect(),
        });
    }

    pub(crate) fn add_plot(
        &mut self,
        section: &str,
        name: &str,
        plot: &Plot,
        skipped: &[SkippedPoint],
    ) {
        let series = plot.series.iter().map(|s| SeriesSummary {
            name: s.name.clone(),
            points: s.points.iter().map(|&(x, y)| [json::number(x), json::number(y)]).collect(),
        });
        self.plots.push(PlotSummary {
            name: name.to_owned(),
            section: section.to_owned(),
            title: plot.title.clone(),
            x_label: plot.x_label.clone(),
            y_label: plot.y_label.clone(),
            log_x: plot.log_x,
            log_y: plot.log_y,
            series: series.collect(),
            skipped: skipped
                .iter()
                .map(|p| serde_json::to_value(p).unwrap_or(Value::Null))
                .collect(),
        });
    }

    pub(crate) fn add_animation(
        &mut self,
        section: &str,
        name: &str,
        caption: &str,
        animation: &Animation,
    ) {
        let (width, height) = animation.size();
        self.animations.push(AnimationSummary {
            name: name.to_owned(),
            section: section.to_owned(),
            caption: caption.to_owned(),
            file: format!("assets/{name}.png"),
            frames: animation.frames.len(),
            width,
            height,
            frame_ms: animation.frame_ms,
        });
    }

    pub(crate) fn add_images(
        &mut self,
        section: &str,
        name: &str,
        caption: &str,
        grid: &ImageGrid,
    ) {
        let images = grid.images.iter().enumerate().map(|(i, img)| {
            serde_json::json!({
                "label": img.label,
                "file": format!("assets/{name}/{i}.png"),
                "width": img.image.width,
                "height": img.image.height,
            })
        });
        self.images.push(ImagesSummary {
            name: name.to_owned(),
            section: section.to_owned(),
            caption: caption.to_owned(),
            file: format!("assets/{name}.png"),
            images: images.collect(),
        });
    }
}
