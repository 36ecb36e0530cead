//! The builtin procedural scenes by name, with parameters, for the CLI and the experiments.
//!
//! A scene spec is `NAME` or `NAME?KEY=VALUE&KEY=VALUE…` — the query-string form the CLI accepts
//! after `builtin:` — for example `forest?trees=20&seed=3` or `island?grass=100000`. Keys are the
//! ones [`builtin_params`] lists (with defaults and ranges); each may be given once. Integers are
//! decimal, numbers anything Rust's `f32` parser accepts, booleans `true`/`false`/`1`/`0`.
//! Unknown scenes, unknown or repeated keys, malformed pairs and out-of-range values are all an
//! [`Error::InvalidParameter`] that names the scene and key and says what is valid.
//!
//! Every builtin also takes `subdivide=N` and `subdivision=midpoint|loop`
//! ([`crate::subdivide::PARAMS`]): the scene is built, then each of its meshes subdivided `N`
//! times (`4^N` as many triangles), e.g. `sphere?subdiv=2&subdivide=2&subdivision=loop`.

use std::sync::LazyLock;

use glam::Vec3;

use super::param::{parse, parse_bool, unknown};
use super::primitives::{cornell_box, cube, icosphere, scene_with};
use super::{
    BlindsParams, BumpyParams, CityParams, CrowdParams, ForestParams, IslandParams, blinds, bumpy,
    city, crowd, forest, island,
};
use crate::subdivide::{PARAMS as SUBDIVISION_PARAMS, Subdivision};
use crate::{Error, Material, Result, Scene};

/// One parameter of a builtin scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamInfo {
    /// The key in a spec.
    pub name: &'static str,
    /// Its default as text (`None` where there is none: the parameter is optional).
    pub default: Option<&'static str>,
    /// What it does and its valid range.
    pub description: &'static str,
}

const fn param(name: &'static str, default: &'static str, description: &'static str) -> ParamInfo {
    ParamInfo { name, default: Some(default), description }
}

/// A builtin scene: name, description, parameters and builder.
struct Builtin {
    name: &'static str,
    description: &'static str,
    params: &'static [ParamInfo],
    build: fn(&[(&str, &str)]) -> Result<Scene>,
}

const FOREST_PARAMS: &[ParamInfo] = &[
    param("trees", "6", "number of trees, 1..=100000"),
    param("leaves", "24000", "leaves per tree (2 triangles each), 0..=1000000"),
    param("cluster", "24", "leaves per tuft, 1..=4096 (1: scattered leaves)"),
    param("depth", "4", "branch levels below the trunk, 0..=6"),
    param("branching", "3", "children per branch, 1..=6"),
    param("seed", "1", "random seed, any u64"),
    param("extent", "10", "side of the square ground, 0.001..=1e6"),
    param("height", "3.5", "mean tree height, (0, 2·extent]"),
    param("leaf_size", "0.016666668", "largest leaf length, (0, extent/10]"),
    param("ground", "8", "quads per side of the ground, 1..=1024"),
    param("alpha", "true", "alpha-masked textured leaves (else untextured kites)"),
    ParamInfo {
        name: "triangles",
        default: None,
        description: "size the forest to at least this many triangles (sets trees, leaves and \
                      extent; not with trees or leaves)",
    },
];

const ISLAND_PARAMS: &[ParamInfo] = &[
    param("seed", "1", "random seed, any u64"),
    param("extent", "20", "side of the square sea, 0.001..=1e6"),
    param("terrain", "128", "terrain quads per side, 8..=2048"),
    param("grass", "40000", "grass blades (3 triangles each), 0..=8000000"),
    param("rocks", "24", "rocks (320 triangles each), 0..=10000"),
    param("blade_height", "0.25", "tallest grass blade, (0, extent/20]"),
    param("blade_width", "0.012", "widest blade base, (0, blade_height]"),
];

const CITY_PARAMS: &[ParamInfo] = &[
    param("blocks", "3", "blocks per side, 1..=64"),
    param("seed", "1", "random seed, any u64"),
    param("detail", "1", "0: plain walls, 1: recessed windows, 2: with sills and mullions"),
    param("block_size", "48", "side of a block with its sidewalk in metres, 16..=1000"),
    param("street_width", "12", "street width in metres, 4..=100"),
    param("max_floors", "16", "most floors of a building (3.2 m each), 2..=200"),
    param("window_spacing", "2.5", "facade bay width (one window per floor), 1..=50"),
    ParamInfo {
        name: "triangles",
        default: None,
        description: "size the city to at least this many triangles (sets blocks and \
                      window_spacing; not with them)",
    },
];

const BLINDS_PARAMS: &[ParamInfo] = &[
    param("slats", "128", "number of slats (12 triangles each), 2..=4096"),
    param("tilt", "20", "slat tilt in degrees, -89..=89 (0 = open)"),
    param("extent", "2", "scene width, 0.001..=1e6"),
];

const CROWD_PARAMS: &[ParamInfo] = &[
    param("walkers", "16", "walking skinned characters (17 joints each), 1..=256"),
    param("rigid", "16", "rotating tori and cubes, 0..=1024"),
    param("sides", "12", "sides of every body tube (3 512 triangles per walker at 12), 8..=64"),
    param("spacing", "2.5", "distance between walker slots, 1.5..=100"),
    param("duration", "4", "length of the looping animation in seconds, 1..=60"),
    param("seed", "1", "random seed, any u64"),
];

const BUMPY_SPHERE_PARAMS: &[ParamInfo] = &[
    param("subdiv", "6", "icosphere subdivisions (20·4^subdiv triangles), 0..=7"),
    param("amplitude", "0.1", "largest displacement (radius 1), (0, 0.5]"),
    param("frequency", "12", "first octave's frequency on the unit sphere, (0, 1e4]"),
    param("octaves", "3", "octaves of noise, 1..=12"),
    param("seed", "1", "random seed, any u64"),
];

const BUMPY_SPECULAR_PARAMS: &[ParamInfo] = &[
    param("subdiv", "6", "icosphere subdivisions (20·4^subdiv triangles), 0..=7"),
    param("amplitude", "0.03", "largest displacement (radius 1), (0, 0.5]"),
    param("frequency", "20", "first octave's frequency on the unit sphere, (0, 1e4]"),
    param("octaves", "2", "octaves of noise, 1..=12"),
    param("seed", "1", "random seed, any u64"),
    param("specular", "0.5", "specular level, [0, 1]"),
    param("shininess", "200", "Blinn-Phong exponent, [0, 1e4]"),
];

const SPHERE_PARAMS: &[ParamInfo] =
    &[param("subdiv", "3", "icosphere subdivisions (20·4^subdiv triangles), 0..=7")];

const BUILTINS: &[Builtin] = &[
    Builtin {
        name: "forest",
        description: "ground and trees with thin branches and many sub-voxel leaves",
        params: FOREST_PARAMS,
        build: |kv| forest(&forest_params(kv)?),
    },
    Builtin {
        name: "island",
        description: "heightfield island in a specular sea, rocks, thin grass blades",
        params: ISLAND_PARAMS,
        build: |kv| island(&island_params(kv)?),
    },
    Builtin {
        name: "city",
        description: "city blocks: buildings with recessed windows, streets, sidewalks, lamps, benches, cars",
        params: CITY_PARAMS,
        build: |kv| city(&city_params(kv)?),
    },
    Builtin {
        name: "blinds",
        description: "tilted two-coloured slats below voxel spacing: directional opacity",
        params: BLINDS_PARAMS,
        build: |kv| blinds(&blinds_params(kv)?),
    },
    Builtin {
        name: "crowd",
        description: "animated: skinned walkers among rotating rigid objects on a static floor",
        params: CROWD_PARAMS,
        build: |kv| crowd(&crowd_params(kv)?),
    },
    Builtin {
        name: "bumpy-sphere",
        description: "closed sphere with fine relief, colour correlated with height (red valleys, green tops)",
        params: BUMPY_SPHERE_PARAMS,
        build: |kv| {
            bumpy("bumpy-sphere", &bumpy_params("bumpy-sphere", BumpyParams::default(), kv)?)
        },
    },
    Builtin {
        name: "bumpy-specular",
        description: "closed sphere with fine relief, one glossy grey material",
        params: BUMPY_SPECULAR_PARAMS,
        build: |kv| {
            bumpy("bumpy-specular", &bumpy_params("bumpy-specular", BumpyParams::specular(), kv)?)
        },
    },
    Builtin {
        name: "cornell",
        description: "the Cornell box with two boxes and a point light",
        params: &[],
        build: |_| Ok(cornell_box()),
    },
    Builtin {
        name: "cube",
        description: "a closed unit cube [-0.5, 0.5]³",
        params: &[],
        build: |_| {
            let m = cube(Vec3::splat(-0.5), Vec3::splat(0.5));
            Ok(scene_with("cube", m, Material::default()))
        },
    },
    Builtin {
        name: "sphere",
        description: "a closed unit icosphere",
        params: SPHERE_PARAMS,
        build: |kv| {
            let mut subdiv = 3;
            for &(k, v) in kv {
                match k {
                    "subdiv" => subdiv = parse("sphere", k, v)?,
                    _ => return Err(unknown("sphere", k, v, &["subdiv"])),
                }
            }
            super::param::check_u32("sphere", "subdiv", subdiv, 0, 7)?;
            Ok(scene_with("sphere", icosphere(Vec3::ZERO, 1.0, subdiv), Material::default()))
        },
    },
];

static NAMES: LazyLock<Vec<(&'static str, &'static str)>> =
    LazyLock::new(|| BUILTINS.iter().map(|b| (b.name, b.description)).collect());

/// The builtin procedural scenes: `(name, description)`.
pub fn builtin_names() -> &'static [(&'static str, &'static str)] {
    &NAMES
}

fn find(name: &str) -> Result<&'static Builtin> {
    BUILTINS.iter().find(|b| b.name == name).ok_or_else(|| Error::InvalidParameter {
        name: "builtin scene".into(),
        value: name.into(),
        reason: format!(
            "unknown; the builtin scenes are: {}",
            BUILTINS.iter().map(|b| b.name).collect::<Vec<_>>().join(", ")
        ),
    })
}

/// The parameters builtin `name` takes, or an error for an unknown name.
pub fn builtin_params(name: &str) -> Result<&'static [ParamInfo]> {
    Ok(find(name)?.params)
}

/// Builds builtin `name` with `params` as `(key, value)` pairs (see the module docs), then
/// subdivides it if the pairs include `subdivide` ([`crate::subdivide::Subdivision`]).
pub fn builtin(name: &str, params: &[(&str, &str)]) -> Result<Scene> {
    let b = find(name)?;
    let mut params = params.to_vec();
    let subdivision = Subdivision::take_from_pairs(name, &mut params)?;
    for (i, &(key, value)) in params.iter().enumerate() {
        if !b.params.iter().any(|p| p.name == key) {
            let valid: Vec<&str> =
                b.params.iter().chain(SUBDIVISION_PARAMS).map(|p| p.name).collect();
            return Err(unknown(name, key, value, &valid));
        }
        if params[..i].iter().any(|&(k, _)| k == key) {
            return Err(Error::InvalidParameter {
                name: format!("{name}.{key}"),
                value: value.into(),
                reason: "given more than once".into(),
            });
        }
    }
    let scene = (b.build)(&params)?;
    match subdivision {
        Some(s) => s.apply(scene),
        None => Ok(scene),
    }
}

/// Splits a spec `NAME[?KEY=VALUE&…]` into its name and pairs, without building anything.
pub fn parse_spec(spec: &str) -> Result<(&str, Vec<(&str, &str)>)> {
    let spec = spec.trim();
    let (name, query) = spec.split_once('?').unwrap_or((spec, ""));
    let bad = |value: &str, reason: &str| Error::InvalidParameter {
        name: format!("scene spec '{spec}'"),
        value: value.into(),
        reason: reason.into(),
    };
    if name.is_empty() {
        return Err(bad(spec, "no scene name; expected NAME[?KEY=VALUE&...]"));
    }
    let mut pairs = Vec::new();
    for pair in query.split('&').filter(|_| !query.is_empty()) {
        match pair.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() => pairs.push((k.trim(), v.trim())),
            _ => return Err(bad(pair, "expected KEY=VALUE between '&'s")),
        }
    }
    Ok((name, pairs))
}

/// Builds the scene a spec `NAME[?KEY=VALUE&…]` names (see the module docs).
pub fn from_spec(spec: &str) -> Result<Scene> {
    let (name, pairs) = parse_spec(spec)?;
    builtin(name, &pairs)
}

/// [`ForestParams`] from spec pairs (keys already checked against [`FOREST_PARAMS`]).
pub(super) fn forest_params(kv: &[(&str, &str)]) -> Result<ForestParams> {
    let mut p = ForestParams::default();
    let mut target = None;
    for &(k, v) in kv {
        let f = "forest";
        match k {
            "trees" => p.trees = parse(f, k, v)?,
            "leaves" => p.leaves_per_tree = parse(f, k, v)?,
            "cluster" => p.leaf_cluster = parse(f, k, v)?,
            "depth" => p.branch_depth = parse(f, k, v)?,
            "branching" => p.branching = parse(f, k, v)?,
            "seed" => p.seed = parse(f, k, v)?,
            "extent" => p.extent = parse(f, k, v)?,
            "height" => p.tree_height = parse(f, k, v)?,
            "leaf_size" => p.leaf_size = parse(f, k, v)?,
            "ground" => p.ground_subdivisions = parse(f, k, v)?,
            "alpha" => p.alpha_leaves = parse_bool(f, k, v)?,
            "triangles" => target = Some((v, parse::<u64>(f, k, v)?)),
            _ => return Err(unknown(f, k, v, &[])),
        }
    }
    if let Some((text, target)) = target {
        if kv.iter().any(|&(k, _)| k == "trees" || k == "leaves") {
            return Err(Error::InvalidParameter {
                name: "forest.triangles".into(),
                value: text.into(),
                reason: "sets trees and leaves itself: give either triangles or trees/leaves"
                    .into(),
            });
        }
        p = p.fit_triangles(target);
    }
    p.validate()?;
    Ok(p)
}

/// [`BumpyParams`] from spec pairs over a preset.
pub(super) fn bumpy_params(
    scene: &str,
    mut p: BumpyParams,
    kv: &[(&str, &str)],
) -> Result<BumpyParams> {
    for &(k, v) in kv {
        match k {
            "subdiv" => p.subdiv = parse(scene, k, v)?,
            "amplitude" => p.amplitude = parse(scene, k, v)?,
            "frequency" => p.frequency = parse(scene, k, v)?,
            "octaves" => p.octaves = parse(scene, k, v)?,
            "seed" => p.seed = parse(scene, k, v)?,
            "specular" => p.specular = parse(scene, k, v)?,
            "shininess" => p.shininess = parse(scene, k, v)?,
            _ => return Err(unknown(scene, k, v, &[])),
        }
    }
    p.validate(scene)?;
    Ok(p)
}

/// [`IslandParams`] from spec pairs.
pub(super) fn island_params(kv: &[(&str, &str)]) -> Result<IslandParams> {
    let mut p = IslandParams::default();
    for &(k, v) in kv {
        let s = "island";
        match k {
            "seed" => p.seed = parse(s, k, v)?,
            "extent" => p.extent = parse(s, k, v)?,
            "terrain" => p.terrain_resolution = parse(s, k, v)?,
            "grass" => p.grass_blades = parse(s, k, v)?,
            "rocks" => p.rocks = parse(s, k, v)?,
            "blade_height" => p.blade_height = parse(s, k, v)?,
            "blade_width" => p.blade_width = parse(s, k, v)?,
            _ => return Err(unknown(s, k, v, &[])),
        }
    }
    p.validate()?;
    Ok(p)
}

/// [`CrowdParams`] from spec pairs.
pub(super) fn crowd_params(kv: &[(&str, &str)]) -> Result<CrowdParams> {
    let mut p = CrowdParams::default();
    for &(k, v) in kv {
        let c = "crowd";
        match k {
            "walkers" => p.walkers = parse(c, k, v)?,
            "rigid" => p.rigid = parse(c, k, v)?,
            "sides" => p.sides = parse(c, k, v)?,
            "spacing" => p.spacing = parse(c, k, v)?,
            "duration" => p.duration = parse(c, k, v)?,
            "seed" => p.seed = parse(c, k, v)?,
            _ => return Err(unknown(c, k, v, &[])),
        }
    }
    p.validate()?;
    Ok(p)
}

/// [`BlindsParams`] from spec pairs.
pub(super) fn blinds_params(kv: &[(&str, &str)]) -> Result<BlindsParams> {
    let mut p = BlindsParams::default();
    for &(k, v) in kv {
        match k {
            "slats" => p.slats = parse("blinds", k, v)?,
            "tilt" => p.tilt_deg = parse("blinds", k, v)?,
            "extent" => p.extent = parse("blinds", k, v)?,
            _ => return Err(unknown("blinds", k, v, &[])),
        }
    }
    p.validate()?;
    Ok(p)
}

/// [`CityParams`] from spec pairs.
pub(super) fn city_params(kv: &[(&str, &str)]) -> Result<CityParams> {
    let mut p = CityParams::default();
    let mut target = None;
    for &(k, v) in kv {
        let c = "city";
        match k {
            "blocks" => p.blocks = parse(c, k, v)?,
            "seed" => p.seed = parse(c, k, v)?,
            "detail" => p.detail = parse(c, k, v)?,
            "block_size" => p.block_size = parse(c, k, v)?,
            "street_width" => p.street_width = parse(c, k, v)?,
            "max_floors" => p.max_floors = parse(c, k, v)?,
            "window_spacing" => p.window_spacing = parse(c, k, v)?,
            "triangles" => target = Some((v, parse::<u64>(c, k, v)?)),
            _ => return Err(unknown(c, k, v, &[])),
        }
    }
    if let Some((text, target)) = target {
        if kv.iter().any(|&(k, _)| k == "blocks" || k == "window_spacing") {
            return Err(Error::InvalidParameter {
                name: "city.triangles".into(),
                value: text.into(),
                reason: "sets blocks and window_spacing itself: give either triangles or them"
                    .into(),
            });
        }
        p.validate()?;
        p = p.fit_triangles(target);
    }
    p.validate()?;
    Ok(p)
}
