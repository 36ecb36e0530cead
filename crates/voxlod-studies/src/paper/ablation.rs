//! The ablation of the paper setup: one deviation at a time, every method's change from the
//! setup on the same views and seeds, and whether the paper's ranking holds under it.

use voxlod_cpu::appearance::AuthorsChoices;
use voxlod_cpu::appearance::subgrid::DirectionalRule;
use voxlod_eval::report::{Cell, Column, Table};

use super::tables::{pair, verdict};
use super::{Background, CaseResult, Lighting, PairedDiff, PaperConfig, PaperResult, Variant};
use crate::Error;

/// One deviation from the paper setup.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Toggle {
    /// The scene's coarse mesh instead of its dense one.
    CoarseMesh,
    /// The red background of the paper's Fig. 10.
    RedBackground,
    /// The scene's own background (voxlod's default runs).
    SceneBackground,
    /// The scene's sun alone, at full strength.
    SunOnly,
    /// voxlod's line-sampled directional opacity instead of the authors' rule.
    LinesOpacityRule,
    /// The paper text's normalized circles (§3.4) instead of the authors' code's rule.
    CirclesOpacityRule,
    /// voxlod's 16 fixed samples per visible face instead of up to 40 random ones.
    FixedFaceSamples,
    /// voxlod's fallback (shade with every stored normal) instead of leaving the voxel
    /// unshaded when no sample faces the viewer.
    StoredNormalsFallback,
    /// voxlod's exact per-ray \[VJK21\] chord instead of the cached per-voxel one.
    PerRayChord,
    /// voxlod's Averages normal flipped toward the viewer instead of used as stored.
    FlippedAveragesNormal,
    /// voxlod's fixed 4-ray pixel pattern instead of a jittered one.
    FixedPixelPattern,
    /// Every one of voxlod's choices at once (the rows above from the representations down).
    AllOurs,
    /// Scores on images cropped to the ground truth's coverage.
    Crop,
}

impl Toggle {
    /// Every deviation, in table order.
    pub const ALL: &[Toggle] = &[
        Toggle::CoarseMesh,
        Toggle::RedBackground,
        Toggle::SceneBackground,
        Toggle::SunOnly,
        Toggle::LinesOpacityRule,
        Toggle::CirclesOpacityRule,
        Toggle::FixedFaceSamples,
        Toggle::StoredNormalsFallback,
        Toggle::PerRayChord,
        Toggle::FlippedAveragesNormal,
        Toggle::FixedPixelPattern,
        Toggle::AllOurs,
        Toggle::Crop,
    ];

    /// Name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::CoarseMesh => "coarse mesh",
            Self::RedBackground => "red background",
            Self::SceneBackground => "scene's background",
            Self::SunOnly => "sun only",
            Self::LinesOpacityRule => "line-sampled opacity (voxlod's)",
            Self::CirclesOpacityRule => "normalized circles (paper's text)",
            Self::FixedFaceSamples => "16 fixed face samples (voxlod's)",
            Self::StoredNormalsFallback => "stored-normals fallback (voxlod's)",
            Self::PerRayChord => "per-ray [VJK21] chord (voxlod's)",
            Self::FlippedAveragesNormal => "Averages normal flipped (voxlod's)",
            Self::FixedPixelPattern => "fixed pixel pattern (voxlod's)",
            Self::AllOurs => "all of voxlod's choices",
            Self::Crop => "cropped scores",
        }
    }

    /// The paper setup with this one deviation.
    pub fn variant(self) -> Variant {
        let mut v = Variant { name: self.name().into(), ..Variant::paper() };
        let ours = AuthorsChoices::default();
        let c = &mut v.choices;
        match self {
            Self::CoarseMesh => v.coarse = true,
            Self::RedBackground => v.background = Background::Red,
            Self::SceneBackground => v.background = Background::Scene,
            Self::SunOnly => v.lighting = Lighting::Sun,
            Self::LinesOpacityRule => c.opacity_rule = DirectionalRule::Lines,
            Self::CirclesOpacityRule => c.opacity_rule = DirectionalRule::Circles,
            Self::FixedFaceSamples => c.face_samples = ours.face_samples,
            Self::StoredNormalsFallback => c.fallback = ours.fallback,
            Self::PerRayChord => c.vjk_chord = ours.vjk_chord,
            Self::FlippedAveragesNormal => c.averages_normal = ours.averages_normal,
            Self::FixedPixelPattern => c.pattern = ours.pattern,
            Self::AllOurs => *c = ours,
            Self::Crop => v.crop = true,
        }
        v
    }
}

/// What the ablation produced: the paper setup and each deviation, per scene and resolution.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AblationResult {
    /// The deviations run, in order.
    pub toggles: Vec<Toggle>,
    /// Every case (the paper setup first per scene and resolution).
    pub result: PaperResult,
}

/// Runs the paper setup and each of `toggles`.
pub fn run(
    config: &PaperConfig,
    toggles: &[Toggle],
    progress: &(dyn Fn(&str) + Sync),
) -> Result<AblationResult, Error> {
    let mut variants = vec![Variant::paper()];
    variants.extend(toggles.iter().map(|t| t.variant()));
    let result = super::run_variants(config, &variants, progress)?;
    Ok(AblationResult { toggles: toggles.to_vec(), result })
}

impl AblationResult {
    /// The paper-setup case of `scene` at `res`.
    fn setup(&self, scene: &str, res: u32) -> Option<&CaseResult> {
        self.result
            .cases
            .iter()
            .find(|c| c.scene == scene && c.resolution == res && c.variant == Variant::paper())
    }

    /// Per scene and resolution: one row per deviation and method, its scores and their paired
    /// change from the paper setup; then one row per deviation with the method that renders
    /// best and the virtual mesh against \[VJK21\] (the paper's claim).
    pub fn tables(&self) -> Result<Vec<Table>, Error> {
        let mut tables = Vec::new();
        let mut keys: Vec<(String, u32)> = Vec::new();
        for c in &self.result.cases {
            if !keys.contains(&(c.scene.clone(), c.resolution)) {
                keys.push((c.scene.clone(), c.resolution));
            }
        }
        for (scene, res) in keys {
            let Some(setup) = self.setup(&scene, res) else { continue };
            let cases: Vec<&CaseResult> = self
                .result
                .cases
                .iter()
                .filter(|c| c.scene == scene && c.resolution == res)
                .collect();
            let mut changes = Table::new(
                format!(
                    "{scene} {res}³: each deviation's change from the paper setup (paired over views × seeds, 95 % bootstrap interval)"
                ),
                vec![
                    Column::text("variant"),
                    Column::text("method"),
                    Column::text("MSE"),
                    Column::text("ΔMSE [95 %]"),
                    Column::text("SSIM"),
                    Column::text("ΔSSIM [95 %]"),
                ],
            );
            let mut ranking = Table::new(
                format!("{scene} {res}³: which method renders best under each deviation"),
                vec![
                    Column::text("variant"),
                    Column::text("best SSIM (lead resolved?)"),
                    Column::text("SSIM order"),
                    Column::text("virtual mesh − [VJK21] ΔSSIM [95 %]"),
                    Column::text("virtual mesh − [VJK21] ΔMSE [95 %]"),
                    Column::text("truth error (MSE)"),
                    Column::text("wall (s)"),
                ],
            );
            for case in &cases {
                for m in &case.methods {
                    let base = setup.method(&m.method);
                    let is_setup = case.variant == Variant::paper();
                    let delta = |f: fn(&super::MethodScores) -> &Vec<f64>, sci: bool| match base {
                        Some(b) if !is_setup => {
                            let d = PairedDiff::of(f(m), f(b));
                            if sci { d.display_sci(2) } else { d.display_fixed(4) }
                        }
                        _ => String::new(),
                    };
                    changes.push_row(vec![
                        Cell::Text(case.variant.name.clone()),
                        Cell::Text(m.method.clone()),
                        Cell::Text(format!("{:.3e}", m.mse_mean())),
                        Cell::Text(delta(|s| &s.mse, true)),
                        Cell::Text(format!("{:.4}", m.ssim_mean())),
                        Cell::Text(delta(|s| &s.ssim, false)),
                    ])?;
                }
                let mut order: Vec<&super::MethodScores> = case.methods.iter().collect();
                order.sort_by(|a, b| b.ssim_mean().total_cmp(&a.ssim_mean()));
                let order = order.iter().map(|m| m.method.as_str()).collect::<Vec<_>>().join(" > ");
                let best = case.best_by_ssim().map_or(String::new(), |(m, resolved)| {
                    format!("{} ({})", m.method, if resolved { "yes" } else { "no" })
                });
                let (vm, vjk) = (case.method("virtual mesh"), case.method("[VJK21]"));
                let (dssim, dmse) = match (vm, vjk) {
                    (Some(a), Some(b)) => {
                        let (mse, ssim) = pair(a, b);
                        (
                            format!(
                                "{} → {}",
                                ssim.display_fixed(4),
                                verdict(&ssim, "virtual mesh", "[VJK21]", true)
                            ),
                            format!(
                                "{} → {}",
                                mse.display_sci(2),
                                verdict(&mse, "virtual mesh", "[VJK21]", false)
                            ),
                        )
                    }
                    _ => (String::new(), String::new()),
                };
                ranking.push_row(vec![
                    Cell::Text(case.variant.name.clone()),
                    Cell::Text(best),
                    Cell::Text(order),
                    Cell::Text(dssim),
                    Cell::Text(dmse),
                    Cell::Text(format!("{:.1e}", case.truth_error_mse)),
                    Cell::Text(format!("{:.1}", case.wall_ms / 1e3)),
                ])?;
            }
            tables.push(ranking);
            tables.push(changes);
        }
        Ok(tables)
    }
}

impl AblationResult {
    /// The report: conditions, the ranking and change tables per scene and resolution, and the
    /// findings of every case.
    pub fn add_to_report(
        &self,
        report: &mut voxlod_eval::report::Report,
        config: &PaperConfig,
    ) -> Result<(), Error> {
        report.heading(2, "Ablation of the paper setup");
        report.text(super::tables::intro(config, &self.result));
        report.text(
            "Each variant changes one condition of the paper setup. ΔMSE and ΔSSIM are the \
             variant's score minus the setup's for the same method, view and seed. A variant that \
             changes the ground truth (mesh, background, lights) changes what is measured as well \
             as how: its Δ says how much the finding depends on that condition.",
        );
        for table in self.tables()? {
            report.table(table);
        }
        for c in self.result.cases.iter().filter(|c| c.variant == Variant::paper()) {
            if let Some(t) = c.adaptive_table()? {
                report.table(t);
            }
        }
        for c in self.result.cases.iter().filter(|c| !c.figure.is_empty()) {
            if c.variant != Variant::paper() && c.variant.name != Toggle::AllOurs.name() {
                continue;
            }
            let name = format!(
                "ablation-{}-{}-{}",
                c.scene,
                c.resolution,
                super::tables::slug(&c.variant.name)
            );
            let caption = format!(
                "{} {}³ ({}), view 0, seed 0: ground truth and each method",
                c.scene, c.resolution, c.variant.name
            );
            let grid =
                voxlod_eval::report::ImageGrid::new(c.figure.len().min(7) as u32, c.figure.clone());
            report.images(name, caption, grid);
        }
        report.heading(3, "Findings per variant");
        let text: Vec<String> = self.result.cases.iter().map(super::tables::findings).collect();
        report.text(text.join("\n\n"));
        Ok(())
    }
}
