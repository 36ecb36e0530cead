//! From bytes to a validated glTF JSON document: the GLB container, JSON deserialization with
//! the failing element located, gltf-json's index validation, and the checks it lacks (a node
//! graph that is a forest, scene roots that are roots).
//!
//! `gltf::Gltf::from_slice` is not used: its GLB reader underflows on a header length below 12,
//! and gltf-json's validation indexes `accessors` with an unchecked POSITION index. Both are
//! checked here first, so no third-party call can panic on bad input.

use std::fmt::Display;
use std::path::Path;

use ::gltf::json;
use json::validation::{Checked, Validate};

use crate::{Error, Result};

/// A glTF error naming the file and the element.
pub(super) fn err(path: &Path, element: impl Display, reason: impl Display) -> Error {
    Error::Gltf { path: path.to_owned(), element: element.to_string(), reason: reason.to_string() }
}

/// Splits a binary glTF into its JSON chunk and optional BIN chunk; text glTF is all JSON.
pub(super) fn split_glb<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    if !bytes.starts_with(b"glTF") {
        return Ok((bytes, None));
    }
    let u32_at =
        |o: usize| bytes.get(o..o + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(err(path, "GLB header", format!("truncated: {} bytes", bytes.len())));
    };
    if version != 2 {
        return Err(err(
            path,
            "GLB header",
            format!("container version {version} (only 2 is supported)"),
        ));
    }
    let length = length as usize;
    if length > bytes.len() || length < 12 {
        return Err(err(
            path,
            "GLB header",
            format!("declares {length} bytes, but the file has {} bytes", bytes.len()),
        ));
    }
    let (mut offset, mut json, mut bin) = (12usize, None, None);
    for chunk in 0.. {
        if offset >= length {
            break;
        }
        let (Some(len), Some(kind)) = (u32_at(offset), u32_at(offset + 4)) else {
            return Err(err(path, format!("GLB chunk {chunk}"), "truncated chunk header"));
        };
        let start = offset + 8;
        let end = start.checked_add(len as usize).filter(|&e| e <= length).ok_or_else(|| {
            err(
                path,
                format!("GLB chunk {chunk}"),
                format!("{len} bytes from offset {start} run past the end ({length})"),
            )
        })?;
        match (chunk, kind) {
            (0, 0x4E4F_534A) => json = Some(&bytes[start..end]),
            (0, _) => return Err(err(path, "GLB chunk 0", "the first chunk must be JSON")),
            (1, 0x004E_4942) => bin = Some(&bytes[start..end]),
            _ => {} // Unknown chunks are ignored, as the specification requires.
        }
        offset = end.next_multiple_of(4);
    }
    let json = json.ok_or_else(|| err(path, "GLB chunk 0", "no JSON chunk"))?;
    Ok((json, bin))
}

/// Deserializes the JSON; on failure, finds the top-level element (e.g. `meshes[0]`) at fault.
/// Also returns the JSON value, whose numbers are `f64` (gltf-json's node transforms are `f32`).
pub(super) fn deserialize(path: &Path, text: &[u8]) -> Result<(json::Root, json::Value)> {
    let value: json::Value =
        json::deserialize::from_slice(text).map_err(|e| err(path, "JSON", e))?;
    let version = value.pointer("/asset/version").and_then(json::Value::as_str);
    match version {
        Some(v) if v.starts_with("2.") => {}
        Some(v) => {
            return Err(err(
                path,
                "asset.version",
                format!("glTF {v} is not supported (only 2.x)"),
            ));
        }
        None => {
            return Err(err(path, "asset.version", "missing or not a string: not a glTF 2.0 file"));
        }
    }
    match json::deserialize::from_slice::<json::Root>(text) {
        Ok(root) => Ok((root, value)),
        Err(e) => {
            // gltf-json requires `scene.nodes`, which glTF 2.0 makes optional: retry with an
            // empty list before reporting.
            let mut patched = value.clone();
            let scenes = patched.get_mut("scenes").and_then(json::Value::as_array_mut);
            let mut changed = false;
            for scene in scenes.into_iter().flatten().filter_map(json::Value::as_object_mut) {
                if !scene.contains_key("nodes") {
                    scene.insert("nodes".into(), json::Value::Array(Vec::new()));
                    changed = true;
                }
            }
            if changed && let Ok(root) = json::deserialize::from_value::<json::Root>(patched) {
                return Ok((root, value));
            }
            let element = locate(&value).unwrap_or_else(|| "JSON".to_owned());
            Err(err(path, element, e))
        }
    }
}

/// The first top-level property (or array element) that does not deserialize on its own.
fn locate(value: &json::Value) -> Option<String> {
    let fails = |key: &str, v: json::Value| {
        let probe = json::deserialize::from_str::<json::Value>(r#"{"asset":{"version":"2.0"}}"#);
        let Ok(mut probe) = probe else { return false };
        if let Some(m) = probe.as_object_mut() {
            m.insert(key.to_owned(), v);
        }
        json::deserialize::from_value::<json::Root>(probe).is_err()
    };
    for (key, v) in value.as_object()? {
        if !fails(key, v.clone()) {
            continue;
        }
        if let Some(items) = v.as_array() {
            for (i, item) in items.iter().enumerate() {
                if fails(key, json::Value::Array(vec![item.clone()])) {
                    return Some(format!("{key}[{i}]"));
                }
            }
        }
        return Some(key.clone());
    }
    None
}

/// Runs gltf-json's validation (every index in range, every enum valid, required extensions
/// supported), after checking the one index its validation reads unchecked.
pub(super) fn validate(path: &Path, root: &json::Root) -> Result<()> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&Checked::Valid(json::mesh::Semantic::Positions));
            if let Some(a) = position.filter(|a| a.value() >= root.accessors.len()) {
                return Err(err(
                    path,
                    format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"),
                    format!(
                        "accessor {} does not exist ({} accessors)",
                        a.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, json::Path::new, &mut |p, e| {
        let p = p();
        // voxlod computes bounds itself: a POSITION accessor without min/max is accepted.
        let minmax = p.as_str().contains("[\"POSITION\"].m");
        if !minmax {
            errors.push((p, e));
        }
    });
    // An unsupported required extension explains everything else (e.g. Draco accessors
    // without a bufferView): report it first.
    errors.sort_by_key(|(p, _)| !p.as_str().starts_with("extensionsRequired"));
    let Some((p, e)) = errors.first() else { return Ok(()) };
    use json::validation::Error as V;
    let reason = match e {
        V::IndexOutOfBounds => "refers to an element that does not exist".to_owned(),
        V::Invalid => "invalid value".to_owned(),
        V::Missing => "required property missing".to_owned(),
        V::Unsupported => "extension not supported by voxlod".to_owned(),
        other => other.to_string(),
    };
    let more = if errors.len() > 1 {
        format!(" (and {} more problems)", errors.len() - 1)
    } else {
        String::new()
    };
    Err(err(path, p, format!("{reason}{more}")))
}

/// Checks that the node graph is a forest (each node at most one parent, no cycles) and that
/// every scene lists only root nodes, once. Returns each node's parent.
pub(super) fn node_parents(path: &Path, root: &json::Root) -> Result<Vec<Option<usize>>> {
    let n = root.nodes.len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for (i, node) in root.nodes.iter().enumerate() {
        for c in node.children.iter().flatten().map(|c| c.value()) {
            if c == i {
                return Err(err(path, format!("nodes[{i}]"), "is its own child (a cycle)"));
            }
            if let Some(p) = parent[c] {
                return Err(err(
                    path,
                    format!("nodes[{c}]"),
                    format!(
                        "has two parents, nodes[{p}] and nodes[{i}]: the node graph must be a forest"
                    ),
                ));
            }
            parent[c] = Some(i);
        }
    }
    // Follow parents from every node; reaching a node of the current walk is a cycle.
    let mut state = vec![0u8; n]; // 0 new, 1 on the current walk, 2 known to reach a root
    for start in 0..n {
        let mut walk = Vec::new();
        let mut i = start;
        while state[i] == 0 {
            state[i] = 1;
            walk.push(i);
            match parent[i] {
                Some(p) => i = p,
                None => break,
            }
        }
        if state[i] == 1 && parent[i].is_some() {
            let from = walk.iter().position(|&w| w == i).unwrap_or(0);
            let mut cycle: Vec<String> =
                walk[from..].iter().rev().map(|w| format!("nodes[{w}]")).collect();
            cycle.push(format!("nodes[{}]", walk[walk.len() - 1]));
            let reason = format!("the node graph has a cycle: {}", cycle.join(" → "));
            return Err(err(path, format!("nodes[{i}]"), reason));
        }
        for w in walk {
            state[w] = 2;
        }
    }
    for (s, scene) in root.scenes.iter().enumerate() {
        let mut seen = std::collections::HashSet::new();
        for r in scene.nodes.iter().map(|r| r.value()) {
            if let Some(p) = parent[r] {
                return Err(err(
                    path,
                    format!("scenes[{s}].nodes"),
                    format!("nodes[{r}] is a child of nodes[{p}], not a root"),
                ));
            }
            if !seen.insert(r) {
                return Err(err(
                    path,
                    format!("scenes[{s}].nodes"),
                    format!("lists nodes[{r}] twice"),
                ));
            }
        }
    }
    Ok(parent)
}
