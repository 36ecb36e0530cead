//! The blend row: the CPU's moved voxels blended on each executor against the CPU's world
//! voxels and sums, and the CPU blend against a brute-force sum in 128-bit integers.

use super::*;

/// The CPU's leaves and sums of `placed` (moving voxels blended, statics merged).
pub(super) fn cpu_blend(
    c: &Case,
    placed: &[Placed],
    filter: Filter,
) -> (Leaves, Vec<(u64, CellSums)>) {
    let records: Vec<AverageRecord> =
        c.caches.iter().flat_map(|x| x.records.iter().copied()).collect();
    let (moving, _) = blend(
        &c.world.grid,
        &[BlendInput { placed, records: &records }],
        filter,
        c.world.statics.len() as u64,
    )
    .unwrap();
    let sums = moving.merge(&c.world.statics);
    let (leaves, _) = sums.resolve(FrameOptions::default().occupancy_threshold).unwrap();
    let min = (FrameOptions::default().occupancy_threshold as f64 * 262_144.0).ceil() as u64;
    let kept = sums
        .codes
        .iter()
        .zip(&sums.sums)
        .filter(|(_, s)| s.weight >= min.max(1) && s.alpha > 0)
        .map(|(&c, &s)| (c, s))
        .collect();
    (leaves, kept)
}

/// Blend: the CPU's moved voxels blended on the GPU, exact; plus the control.
pub fn blend_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let (mut differ, mut worst_payload, mut leaves_total, mut control_differ) =
        (0u64, 0.0f64, 0, 0u64);
    let mut first = String::new();
    for c in cases() {
        let up = match &k {
            Some(k) => Some(k.upload(&c.world, &c.caches).map_err(e)?),
            None => None,
        };
        for filter in FILTERS {
            let options = FrameOptions { filter, ..FrameOptions::default() };
            let placed = cpu_placed(c, &frames(c, &options), filter);
            let (want_leaves, want_sums) = cpu_blend(c, &placed, filter);
            leaves_total += want_leaves.len();
            let run = |placed: &[Placed]| -> Result<Blended, String> {
                match (&k, &up) {
                    (Some(k), Some(up)) => {
                        let buf = k.upload_placed(placed).map_err(e)?;
                        let leaves =
                            k.blend(up, &buf, filter, options.occupancy_threshold).map_err(e)?;
                        let (coords, payload, sums) = k.read_leaves(&leaves).map_err(e)?;
                        Ok((coords.into_iter().map(morton::encode).collect(), payload, sums))
                    }
                    _ => {
                        // The CPU row: the brute-force 128-bit sum of every contribution.
                        let oracle = brute_force(c, placed, filter);
                        let (leaves, _) = cpu_blend(c, placed, filter);
                        let codes = leaves.iter().map(|l| l.0).collect();
                        let sums = leaves.iter().map(|l| oracle[&l.0]).collect();
                        Ok((codes, leaves.iter().map(|l| l.1).collect(), sums))
                    }
                }
            };
            let (codes, payload, sums) = run(&placed)?;
            let want_codes: Vec<u64> = want_leaves.iter().map(|l| l.0).collect();
            let mut bad = 0u64;
            if codes != want_codes {
                bad += codes.len().abs_diff(want_codes.len()) as u64
                    + codes.iter().zip(&want_codes).filter(|(a, b)| a != b).count() as u64;
            }
            for ((s, (_, w)), (p, (_, wp))) in
                sums.iter().zip(&want_sums).zip(payload.iter().zip(&want_leaves))
            {
                let (a, b): (&[u32], &[u32]) = (
                    bytemuck::cast_slice(std::slice::from_ref(s)),
                    bytemuck::cast_slice(std::slice::from_ref(w)),
                );
                bad += a.iter().zip(b).filter(|(x, y)| x != y).count() as u64;
                worst_payload = worst_payload.max(p.max_abs_diff(wp) as f64);
            }
            if bad > 0 && first.is_empty() {
                first = format!("{} {}: {bad} differ", c.name, filter.name());
            }
            differ += bad;
            // Control: one voxel's fraction moved by a sixty-fourth must change the sums.
            if filter == Filter::EightNeighbour {
                let mut perturbed = placed.clone();
                if let Some(p) = perturbed.iter_mut().find(|p| p.status == 0 && p.frac & 0xff < 64)
                {
                    p.frac += 1;
                }
                let (_, _, sums) = run(&perturbed)?;
                let changed = sums.len() != want_sums.len()
                    || sums.iter().zip(&want_sums).any(|(a, (_, b))| a != b);
                control_differ += u64::from(changed);
            }
        }
    }
    let controls = cases().len() as u64;
    let pass = differ == 0 && worst_payload <= PAYLOAD && control_differ == controls;
    Ok(Measure {
        max_error: differ as f64,
        bound: 0.0,
        pass,
        note: format!(
            "{leaves_total} leaves: {differ} codes/sum words differ{}; payloads within {worst_payload:.2e} (bound {PAYLOAD:e}); control (one fraction +1/64) caught {control_differ}/{controls}",
            if first.is_empty() { String::new() } else { format!(" ({first})") }
        ),
    })
}

pub(super) fn brute_force(
    c: &Case,
    placed: &[Placed],
    filter: Filter,
) -> std::collections::BTreeMap<u64, CellSums> {
    let records: Vec<AverageRecord> =
        c.caches.iter().flat_map(|x| x.records.iter().copied()).collect();
    let mut out: std::collections::BTreeMap<u64, [i128; 8]> = Default::default();
    let table = voxlod_octree::dynamic::linear12_table();
    let g = &c.world.grid;
    for (p, r) in placed.iter().zip(&records) {
        if p.status != 0 {
            continue;
        }
        for k in 0..filter.corners() {
            let (cell, w) = voxlod_octree::dynamic::blend::corner(p, k, filter);
            if w == 0 || cell.min_element() < 0 || !cell.as_uvec3().cmplt(g.dims).all() {
                continue;
            }
            let e = out.entry(morton::encode(cell.as_uvec3())).or_default();
            let (w, a) = (w as i128, r.opacity as i128);
            e[0] += w;
            e[1] += w * a;
            for i in 0..3 {
                e[2 + i] += w * a * table[r.color[i] as usize] as i128;
                e[5 + i] += w * a * p.normal[i] as i128;
            }
        }
    }
    for (code, s) in c.world.statics.codes.iter().zip(&c.world.statics.sums) {
        let e = out.entry(*code).or_default();
        let v = [
            s.weight as i128,
            s.alpha as i128,
            s.color[0] as i128,
            s.color[1] as i128,
            s.color[2] as i128,
            s.normal[0] as i128,
            s.normal[1] as i128,
            s.normal[2] as i128,
        ];
        for i in 0..8 {
            e[i] += v[i];
        }
    }
    out.into_iter()
        .map(|(k, e)| {
            (
                k,
                CellSums {
                    weight: e[0] as u64,
                    alpha: e[1] as u64,
                    color: [e[2] as u64, e[3] as u64, e[4] as u64],
                    normal: [e[5] as i64, e[6] as i64, e[7] as i64],
                },
            )
        })
        .collect()
}
