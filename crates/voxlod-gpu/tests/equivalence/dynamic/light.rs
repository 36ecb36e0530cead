//! The light rows: light injection into a frame's leaves, and whole frames cone traced, against
//! voxlod-cone's `inject` and `ConeTracer`.

use super::*;

/// Per-value relative errors (absolute below 1) tallied against [`BOUND`] and [`HARD`].
#[derive(Default)]
pub(super) struct Tally {
    values: usize,
    over: usize,
    worst: f64,
}

/// The CPU's injected radiance per leaf (Morton order), for shadows `shadows`.
pub(super) fn cpu_injected(c: &Case, shadows: &Shadows) -> Vec<[f32; 4]> {
    let options = FrameOptions::default();
    let objects: Vec<(&VoxelCache, &Placement)> = c.caches.iter().zip(&c.placements).collect();
    let (geometry, _) = c.world.octree(&objects, &options).unwrap();
    let radiance: Octree<RadiancePayload> = inject(&geometry, &c.light, shadows).unwrap();
    let level = radiance.level(0);
    level
        .payload
        .iter()
        .filter(|p| p.opacity > 0.0)
        .map(|p| [p.radiance_alpha[0], p.radiance_alpha[1], p.radiance_alpha[2], p.opacity])
        .collect()
}

/// Inject: the GPU's radiance per leaf against the CPU's; plus the control.
pub fn inject_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let (mut tally, mut control) = (Tally::default(), Tally::default());
    for c in cases() {
        let want = cpu_injected(c, &Shadows::MARCH);
        let perturbed =
            cpu_injected(c, &Shadows::March { offset_voxels: 1.5, step_factor: 0.5 * 1.05 });
        let got: Vec<[f32; 4]> = match &k {
            None => {
                // The CPU row: without shadows, the injection is the Lambert formula per leaf.
                let objects: Vec<(&VoxelCache, &Placement)> =
                    c.caches.iter().zip(&c.placements).collect();
                let (geometry, _) = c.world.octree(&objects, &FrameOptions::default()).unwrap();
                let unshadowed = cpu_injected(c, &Shadows::None);
                let leaves = voxlod_cone::occupied_leaves(&geometry);
                for ((cell, p), r) in leaves.iter().zip(&unshadowed) {
                    let centre = c.world.grid.voxel_center(*cell).as_vec3();
                    let (l, irr, _) = c.light.at(centre).unwrap();
                    let n = p.normal();
                    let ndl = if n == Vec3::ZERO { 0.5 } else { n.dot(l).max(0.0) };
                    let expected = p.color() * std::f32::consts::FRAC_1_PI * irr * ndl * p.opacity;
                    for i in 0..3 {
                        tally.add(r[i], expected[i]);
                    }
                }
                continue;
            }
            Some(k) => {
                let up = k.upload(&c.world, &c.caches).map_err(e)?;
                let options = FrameOptions::default();
                let frame = k
                    .frame(&up, &c.caches, &c.placements, &options, &c.light, &Shadows::MARCH)
                    .map_err(e)?;
                let raw: Vec<AveragePayload> = bytemuck::pod_collect_to_vec(
                    &k_ctx(backend)
                        .read(
                            &frame.injected,
                            frame.leaves.count * size_of::<AveragePayload>() as u64,
                        )
                        .map_err(e)?,
                );
                raw.iter()
                    .map(|p| [p.color_alpha[0], p.color_alpha[1], p.color_alpha[2], p.opacity])
                    .collect()
            }
        };
        if got.len() != want.len() {
            return Err(format!("{}: {} leaves, expected {}", c.name, got.len(), want.len()));
        }
        for (g, (w, p)) in got.iter().zip(want.iter().zip(&perturbed)) {
            for i in 0..4 {
                tally.add(g[i], w[i]);
                control.add(g[i], p[i]);
            }
        }
    }
    let caught = !control.passes() || matches!(backend, Executor::Cpu);
    Ok(Measure {
        max_error: tally.worst,
        bound: BOUND,
        pass: tally.passes() && caught,
        note: format!(
            "{}; control (step ×1.05): {} → {}",
            tally.note(),
            control.note(),
            if matches!(backend, Executor::Cpu) {
                "n/a on the CPU row"
            } else if caught {
                "caught"
            } else {
                "NOT caught"
            }
        ),
    })
}

/// Frame: the whole frame on the device, cone traced, against the CPU pipeline and tracer.
pub fn frame_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let c = &cases()[0];
    let options = FrameOptions::default();
    let trace = TraceOptions { ao_radius: 1.0, ..TraceOptions::default() };
    let query = ConeQuery { ambient_occlusion: true, diffuse: true, specular: false };
    let mut pipeline: FramePipeline<RadiancePayload> =
        FramePipeline::new(&c.world, &c.caches, options, c.light, Shadows::MARCH);
    let (_, radiance, _) = pipeline.frame(&c.placements).map_err(|e| e.to_string())?;
    let tracer = ConeTracer::new(radiance, trace).map_err(|e| e.to_string())?;
    let want: Vec<_> = c.points.iter().map(|p| reference(&tracer, p, query)).collect();
    let got = match &k {
        None => {
            // The CPU row: the pipeline equals the composition of its steps, bit for bit.
            let objects: Vec<(&VoxelCache, &Placement)> =
                c.caches.iter().zip(&c.placements).collect();
            let (geometry, _) = c.world.octree(&objects, &options).unwrap();
            let r: Octree<RadiancePayload> = inject(&geometry, &c.light, &Shadows::MARCH).unwrap();
            let t = ConeTracer::new(&r, trace).unwrap();
            c.points.iter().map(|p| reference(&t, p, query)).collect::<Vec<_>>()
        }
        Some(k) => {
            let up = k.upload(&c.world, &c.caches).map_err(e)?;
            let frame = k
                .frame(&up, &c.caches, &c.placements, &options, &c.light, &Shadows::MARCH)
                .map_err(e)?;
            k.trace(&frame, &trace, query, &c.points, c.width).map_err(e)?
        }
    };
    let mut tally = Tally::default();
    for (g, w) in got.iter().zip(&want) {
        tally.add(g.ao, w.ao);
        for i in 0..3 {
            tally.add(g.diffuse[i], w.diffuse[i]);
        }
    }
    let hits = c.points.iter().filter(|p| p.normal != Vec3::ZERO).count();
    Ok(Measure {
        max_error: tally.worst,
        bound: BOUND,
        pass: tally.passes() && got.len() == want.len(),
        note: format!("{} ({hits} shading points on the posed crowd)", tally.note()),
    })
}

impl Tally {
    fn add(&mut self, got: f32, want: f32) {
        let d = (got as f64 - want as f64).abs() / (want.abs() as f64).max(1.0);
        self.values += 1;
        self.worst = self.worst.max(d);
        self.over += usize::from(d > BOUND);
    }
    fn passes(&self) -> bool {
        self.worst <= HARD && (self.values - self.over) as f64 >= FRACTION * self.values as f64
    }
    fn note(&self) -> String {
        format!("{} values, {} over {BOUND:e}, worst {:.2e}", self.values, self.over, self.worst)
    }
}
