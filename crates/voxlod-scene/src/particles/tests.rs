use glam::Vec3;

use super::*;

fn puff() -> Particle {
    Particle {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: 1.0,
        velocity: Vec3::new(0.0, 1.0, 0.0),
        displacement: 0.5,
        color: Vec3::ONE,
        density: 2.0,
        color_outer: Vec3::ZERO,
        growth: 0.5,
        birth: 1.0,
        lifetime: 2.0,
        spin: 0.0,
        spin_rate: 0.25,
        color_mode: ColorMode::Constant as u32,
        flags: 0,
        _pad: [0; 2],
    }
}

#[test]
fn layouts_are_what_a_gpu_reads() {
    assert_eq!(std::mem::size_of::<Particle>(), 96);
    assert_eq!(std::mem::size_of::<DisplacedSphere>(), 64);
    assert_eq!(std::mem::offset_of!(Particle, birth), 64);
    assert_eq!(std::mem::offset_of!(DisplacedSphere, rot_cos), 48);
}

#[test]
fn bad_fields_name_the_particle_and_the_field() {
    type Spoil = fn(&mut Particle);
    let cases: [(&str, Spoil); 6] = [
        ("radius", |p| p.radius = -1.0),
        ("center", |p| p.center.y = f32::NAN),
        ("density", |p| p.density = f32::INFINITY),
        ("lifetime", |p| p.lifetime = 0.0),
        ("color", |p| p.color.x = -0.1),
        ("color_mode", |p| p.color_mode = 7),
    ];
    for (field, spoil) in cases {
        let mut particles = vec![puff(); 5];
        spoil(&mut particles[3]);
        let system =
            ParticleSystem { particles, displacement: DisplacementMap::constant(0.5), time: 0.0 };
        let err = system.validate().unwrap_err();
        assert!(
            matches!(err, Error::InvalidParticle { index: 3, field: f, .. } if f == field),
            "{field}: {err}"
        );
        assert!(err.to_string().contains("particle 3"), "{err}");
    }
    let mut p = puff();
    p.lifetime = f32::INFINITY;
    p.validate(0).unwrap();
}

#[test]
fn time_moves_grows_fades_and_spins() {
    let p = puff();
    assert!(p.at(0.5).is_none(), "before birth");
    assert!(p.at(3.5).is_none(), "after death");
    let s = p.at(2.0).unwrap();
    assert_eq!(s.center, Vec3::new(1.0, 3.0, 3.0));
    assert_eq!(s.inner, 1.5);
    assert_eq!(s.amplitude, 0.75);
    assert_eq!(s.outer(), 2.25);
    assert_eq!(s.density, 1.0);
    // A quarter turn: +x maps onto −z in the look-up frame.
    assert!((s.rot_cos).abs() < 1e-6 && (s.rot_sin - 1.0).abs() < 1e-6, "{s:?}");
}

#[test]
fn cube_map_is_continuous_bounded_and_consistent_with_its_texels() {
    let map = DisplacementMap::noise(7, 16, 3.0, 4).unwrap();
    let mut rng = crate::procedural::Rng::new(1);
    let mut spread = (1.0f32, 0.0f32);
    for _ in 0..5_000 {
        let d = rng.unit_vector();
        let v = map.sample(d);
        assert!((0.0..=1.0).contains(&v), "{v} at {d}");
        assert!((v - map.sample(d * 3.7)).abs() < 1e-5, "length does not matter");
        spread = (spread.0.min(v), spread.1.max(v));
        // Nearby directions within one face (away from its edges: faces are not filtered
        // across) read nearby values.
        let mut c = d.abs().to_array();
        c.sort_by(f32::total_cmp);
        if c[2] - c[1] < 1e-2 {
            continue;
        }
        let e = map.sample((d + Vec3::splat(1e-4)).normalize());
        assert!((e - v).abs() < 0.05, "jump {v} → {e} at {d}");
    }
    assert!(spread.1 - spread.0 > 0.3, "noise has contrast: {spread:?}");
    // A texel centre reads exactly its texel.
    let n = 16usize;
    let (i, j) = (5usize, 9usize);
    let dir = Vec3::new(
        1.0,
        (i as f32 + 0.5) / n as f32 * 2.0 - 1.0,
        (j as f32 + 0.5) / n as f32 * 2.0 - 1.0,
    );
    assert!((map.sample(dir) - map.texels()[j * n + i]).abs() < 1e-5);
    assert!(map.sample(Vec3::ZERO).is_finite());
    assert!(DisplacementMap::noise(1, 0, 3.0, 4).is_err());
    assert!(DisplacementMap::noise(1, 8, f32::NAN, 4).is_err());
}

#[test]
fn cube_map_sample_equals_the_plain_lookup_bit_for_bit() {
    for size in [1, 2, 16, 32] {
        let map = DisplacementMap::noise(5, size, 3.0, 4).unwrap();
        let mut rng = crate::procedural::Rng::new(size as u64);
        let mut dirs: Vec<Vec3> =
            (0..20_000).map(|_| rng.unit_vector() * rng.range(0.01, 40.0)).collect();
        // Ties between axes, axes of both signs, the zero vector, signed zeros, non-finite.
        for a in [0.0f32, -0.0, 1.0, -1.0, 0.5, -2.0] {
            for b in [0.0f32, -0.0, 1.0, -1.0, 2.0] {
                for c in [0.0f32, 1.0, -1.0, f32::NAN, f32::INFINITY] {
                    dirs.extend([Vec3::new(a, b, c), Vec3::new(c, a, b), Vec3::new(b, c, a)]);
                }
            }
        }
        for d in dirs {
            assert_eq!(map.sample(d).to_bits(), map.sample_plain(d).to_bits(), "at {d}");
        }
    }
}

#[test]
fn four_lane_lookup_equals_the_scalar_lookup_bit_for_bit() {
    use glam::Vec4;
    for size in [1, 2, 16, 32] {
        let map = DisplacementMap::noise(7, size, 3.0, 4).unwrap();
        let mut rng = crate::procedural::Rng::new(100 + size as u64);
        let mut dirs: Vec<Vec3> =
            (0..20_000).map(|_| rng.unit_vector() * rng.range(0.01, 40.0)).collect();
        // Ties between axes, axes of both signs, the zero vector, signed zeros, non-finite.
        for a in [0.0f32, -0.0, 1.0, -1.0, 0.5, -2.0] {
            for b in [0.0f32, -0.0, 1.0, -1.0, 2.0] {
                for c in [0.0f32, 1.0, -1.0, f32::NAN, f32::INFINITY] {
                    dirs.extend([Vec3::new(a, b, c), Vec3::new(c, a, b), Vec3::new(b, c, a)]);
                }
            }
        }
        let s = DisplacedSphere { rot_cos: 0.6, rot_sin: -0.8, ..Default::default() };
        for quad in dirs.chunks(4) {
            let lane = |i: usize| quad[i.min(quad.len() - 1)];
            let (x, y, z) = (
                Vec4::from_array([0, 1, 2, 3].map(|i| lane(i).x)),
                Vec4::from_array([0, 1, 2, 3].map(|i| lane(i).y)),
                Vec4::from_array([0, 1, 2, 3].map(|i| lane(i).z)),
            );
            let (four, rotated) = (map.sample4(x, y, z), s.displacement4(&map, x, y, z));
            let [lo, hi] = map.bounds();
            for i in 0..4 {
                let d = lane(i);
                if d.is_finite() {
                    assert!((lo..=hi).contains(&four[i]), "at {d}: {} not in {lo}..{hi}", four[i]);
                }
                let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan();
                assert!(same(four[i], map.sample(d)), "at {d}: {} {}", four[i], map.sample(d));
                let r = s.displacement(&map, d);
                assert!(same(rotated[i], r), "rotated, at {d}: {} {r}", rotated[i]);
            }
        }
        // The bounds are the texel range, barely widened.
        let [lo, hi] = map.bounds();
        let t = map.texels();
        let (tmin, tmax) = t.iter().fold((1.0f32, 0.0f32), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(lo <= tmin && tmin - lo <= 1e-6 && hi >= tmax && hi - tmax <= 1e-6);
    }
    let flat = DisplacementMap::constant(0.25);
    assert_eq!(flat.sample4(Vec4::ONE, Vec4::ZERO, -Vec4::ONE), Vec4::splat(0.25));
}

#[test]
fn presets_are_deterministic_valid_and_sized() {
    let a = smoke_column(&SmokeParams { count: 500, ..Default::default() }).unwrap();
    let b = smoke_column(&SmokeParams { count: 500, ..Default::default() }).unwrap();
    assert_eq!(a, b);
    let c = smoke_column(&SmokeParams { count: 500, seed: 9, ..Default::default() }).unwrap();
    assert_ne!(a.particles, c.particles);
    let live = a.at(a.time);
    assert!(live.len() > 450, "{}", live.len());
    let (lo, hi) = bounds(&live).unwrap();
    assert!(hi.y - lo.y > 4.0 && hi.y > 5.0, "a tall column: {lo} {hi}");
    let e = explosion(&ExplosionParams { count: 300, ..Default::default() }).unwrap();
    let live = e.at(e.time);
    assert!(live.iter().any(|s| s.emissive()) && live.iter().any(|s| !s.emissive()));
    let k = cloud_bank(&CloudParams { count: 300, ..Default::default() }).unwrap();
    assert_eq!(k.at(k.time).len(), 300);
    for bad in [0, MAX_PARTICLES + 1] {
        assert!(smoke_column(&SmokeParams { count: bad, ..Default::default() }).is_err());
    }
    let big = smoke_column(&SmokeParams { count: MAX_PARTICLES, ..Default::default() }).unwrap();
    assert_eq!(big.particles.len(), MAX_PARTICLES);
}

#[test]
fn colour_modes() {
    let mut s = puff().at(1.0).unwrap();
    s.color_outer = Vec3::ZERO;
    s.color_mode = ColorMode::RadialRamp as u32;
    assert_eq!(s.color_at(0.0, 0.0), Vec3::ONE);
    assert_eq!(s.color_at(s.outer(), 0.0), Vec3::ZERO);
    s.color_mode = ColorMode::DisplacementAo as u32;
    assert_eq!(s.color_at(0.3, 1.0), Vec3::ONE);
    assert_eq!(s.color_at(0.3, 0.0), Vec3::splat(AO_FLOOR));
}
