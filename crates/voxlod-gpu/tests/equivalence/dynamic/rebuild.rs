//! The rebuild row: the octree each executor builds from its own leaves against the CPU's
//! topology and payloads.

use super::*;

/// Entries of two flat octrees' topologies that differ.
pub(super) fn topology_diff(a: &FlatOctree<AveragePayload>, e: &FlatOctree<AveragePayload>) -> u64 {
    let count = |x: usize, y: usize, d: usize| (x.abs_diff(y) + d) as u64;
    let mut bad = u64::from(a.depth != e.depth);
    bad += count(
        a.levels.len(),
        e.levels.len(),
        a.levels.iter().zip(&e.levels).filter(|(x, y)| x != y).count(),
    );
    bad += count(
        a.nodes.len(),
        e.nodes.len(),
        a.nodes.iter().zip(&e.nodes).filter(|(x, y)| x != y).count(),
    );
    bad += count(
        a.tiles.len(),
        e.tiles.len(),
        a.tiles.iter().zip(&e.tiles).filter(|(x, y)| x != y).count(),
    );
    for (l, lv) in e.levels.iter().enumerate() {
        for i in lv.first..lv.first + lv.count {
            for axis in 0..3 {
                bad += u64::from(a.neighbour(l as u32, i, axis) != e.neighbour(l as u32, i, axis));
            }
        }
    }
    bad
}

/// Rebuild: the GPU's octree from its own leaves against the CPU's from the CPU's leaves.
pub fn rebuild_scenes(backend: &Executor) -> Result<Measure, String> {
    let k = kernels(backend)?;
    let e = |e: voxlod_gpu::Error| e.to_string();
    let (mut differ, mut worst, mut control_caught, mut nodes) = (0u64, 0.0f64, 0u64, 0usize);
    let options = FrameOptions::default();
    let bound = PAYLOAD + 8.0 * 7.0 / (1u64 << 24) as f64;
    for c in cases() {
        let (cpu_leaves, _) = {
            let objects: Vec<(&VoxelCache, &Placement)> =
                c.caches.iter().zip(&c.placements).collect();
            c.world.leaves(&objects, &options).unwrap()
        };
        let cpu = FlatOctree::from_octree(
            &Octree::from_morton_sorted(c.world.grid, cpu_leaves.clone(), &options.build).unwrap(),
        )
        .unwrap();
        nodes += cpu.nodes.len();
        let got = match &k {
            None => {
                let voxels: Vec<(UVec3, AveragePayload)> =
                    cpu_leaves.iter().map(|(code, p)| (morton::decode(*code), *p)).collect();
                FlatOctree::build_level_by_level(c.world.grid, &voxels, &options.build)
                    .map_err(|e| e.to_string())?
            }
            Some(k) => {
                let up = k.upload(&c.world, &c.caches).map_err(e)?;
                let f = frames(c, &options);
                let placed = k.transform(&up, &f, options.filter).map_err(e)?;
                let leaves = k
                    .blend(&up, &placed, options.filter, options.occupancy_threshold)
                    .map_err(e)?;
                let octree = voxlod_gpu::octree::OctreeBuilder::new(k_ctx(backend)).map_err(e)?;
                let tree = octree
                    .build_device(
                        &c.world.grid,
                        &leaves.coords,
                        &leaves.payload,
                        leaves.count as usize,
                        &options.build,
                    )
                    .map_err(e)?;
                tree.read_back().map_err(e)?
            }
        };
        differ += topology_diff(&got, &cpu);
        if got.payload.len() == cpu.payload.len() {
            for (a, b) in got.payload.iter().zip(&cpu.payload) {
                worst = worst.max(a.max_abs_diff(b) as f64);
            }
        }
        // Control: the CPU octree without its first leaf must differ.
        let mut fewer = cpu_leaves;
        fewer.remove(0);
        let dropped = FlatOctree::from_octree(
            &Octree::from_morton_sorted(c.world.grid, fewer, &options.build).unwrap(),
        )
        .unwrap();
        let payload_moved = got.payload.len() != dropped.payload.len()
            || got
                .payload
                .iter()
                .zip(&dropped.payload)
                .any(|(a, b)| a.max_abs_diff(b) as f64 > bound);
        control_caught += u64::from(topology_diff(&got, &dropped) > 0 || payload_moved);
    }
    let controls = cases().len() as u64;
    Ok(Measure {
        max_error: differ as f64,
        bound: 0.0,
        pass: differ == 0 && worst <= bound && control_caught == controls,
        note: format!(
            "{nodes} nodes: {differ} topology entries differ; payloads within {worst:.2e} (bound {bound:.2e}); control (one leaf dropped) caught {control_caught}/{controls}"
        ),
    })
}
