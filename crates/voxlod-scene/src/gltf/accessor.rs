//! Bounds-checked buffer views and accessors (strided, sparse, normalized, matrix columns
//! aligned), with errors naming the view or accessor, the element at fault and what the
//! accessor was read for.

use std::path::Path;

use ::gltf::json;
use json::accessor::{ComponentType, Type};
use json::validation::Checked;

use super::parse::err;
use crate::Result;

/// Most elements a view-less (all-zero or sparse-only) accessor may have.
const MAX_VIRTUAL_ELEMENTS: usize = 1 << 26;

/// Bounds-checked access to the document's binary data.
pub(super) struct Data<'a> {
    /// The file, for messages.
    pub path: &'a Path,
    /// The document.
    pub root: &'a json::Root,
    /// The loaded buffers.
    pub buffers: &'a [Vec<u8>],
}

/// An accessor's values, every component widened to f64 (not yet normalized).
pub(super) struct Values {
    /// Component type.
    pub ty: ComponentType,
    /// Components per element.
    pub dims: usize,
    /// Whether integer components are normalized.
    pub normalized: bool,
    /// `count × dims` components.
    pub raw: Vec<f64>,
}

fn component(ty: ComponentType, b: &[u8]) -> f64 {
    match ty {
        ComponentType::I8 => f64::from(b[0] as i8),
        ComponentType::U8 => f64::from(b[0]),
        ComponentType::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        ComponentType::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        ComponentType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        ComponentType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    }
}

fn type_name(t: Type) -> &'static str {
    ["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"][t as usize - 1]
}

impl Data<'_> {
    /// The bytes of buffer view `v`, checked against its buffer.
    pub fn view(&self, v: usize) -> Result<(&[u8], Option<usize>)> {
        let element = format!("bufferViews[{v}]");
        let view = self
            .root
            .buffer_views
            .get(v)
            .ok_or_else(|| err(self.path, &element, "does not exist"))?;
        let b = view.buffer.value();
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| err(self.path, &element, format!("buffers[{b}] does not exist")))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(view.byte_length.0);
        match end.and_then(|e| buffer.get(usize::try_from(start).ok()?..usize::try_from(e).ok()?)) {
            Some(bytes) => Ok((bytes, view.byte_stride.map(|s| s.0))),
            None => Err(err(
                self.path,
                element,
                format!(
                    "bytes {start}..{} lie beyond buffers[{b}] ({} bytes)",
                    end.map_or("∞".into(), |e| e.to_string()),
                    buffer.len()
                ),
            )),
        }
    }

    /// Reads accessor `a` whole (strides, sparse substitution), checking every range. `usage`
    /// says what the accessor is for, for messages.
    pub fn read(&self, a: usize, usage: &str) -> Result<Values> {
        let element = format!("accessors[{a}]");
        let bad = |reason: String| err(self.path, &element, format!("{reason} ({usage})"));
        let acc = self.root.accessors.get(a).ok_or_else(|| bad("does not exist".into()))?;
        let (Checked::Valid(ct), Checked::Valid(t)) = (&acc.component_type, &acc.type_) else {
            return Err(bad("invalid componentType or type".into()));
        };
        let (ty, dims) = (ct.0, t.multiplicity());
        let size = ty.size();
        // Matrix columns start on 4-byte boundaries.
        let (cols, rows) = match t {
            Type::Mat2 => (2, 2),
            Type::Mat3 => (3, 3),
            Type::Mat4 => (4, 4),
            _ => (1, dims),
        };
        let col_bytes = (rows * size).next_multiple_of(if cols > 1 { 4 } else { 1 });
        let elem = cols * col_bytes;
        let count = usize::try_from(acc.count.0).map_err(|_| bad("count too large".into()))?;
        let decode = |bytes: &[u8], out: &mut Vec<f64>| {
            for c in 0..cols {
                for r in 0..rows {
                    out.push(component(ty, &bytes[c * col_bytes + r * size..]));
                }
            }
        };
        let mut raw = Vec::new();
        match acc.buffer_view {
            Some(v) => {
                let (bytes, stride) = self.view(v.value())?;
                let stride = stride.unwrap_or(elem);
                if stride < elem {
                    return Err(bad(format!(
                        "byteStride {stride} of bufferViews[{}] is less than an element ({elem} bytes)",
                        v.value()
                    )));
                }
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                let need = (count as u64)
                    .checked_sub(1)
                    .map_or(Some(0), |last| {
                        last.checked_mul(stride as u64)?.checked_add(elem as u64 + offset)
                    })
                    .filter(|&n| n <= bytes.len() as u64);
                let Some(_) = need else {
                    return Err(bad(format!(
                        "{count} elements of {elem} bytes (stride {stride}) from offset {offset} \
                         run past the end of bufferViews[{}] ({} bytes)",
                        v.value(),
                        bytes.len()
                    )));
                };
                raw.reserve(count * dims);
                for i in 0..count {
                    decode(&bytes[offset as usize + i * stride..], &mut raw);
                }
            }
            None if count <= MAX_VIRTUAL_ELEMENTS => raw.resize(count * dims, 0.0),
            None => return Err(bad(format!("{count} elements without a bufferView is too many"))),
        }
        if let Some(sparse) = &acc.sparse {
            let n = usize::try_from(sparse.count.0).unwrap_or(usize::MAX);
            let Checked::Valid(ict) = &sparse.indices.component_type else {
                return Err(bad("invalid sparse.indices.componentType".into()));
            };
            let slice = |v: usize, offset: u64, width: usize, what: &str| -> Result<Vec<u8>> {
                let (bytes, _) = self.view(v)?;
                let len = (n as u64).checked_mul(width as u64).and_then(|l| l.checked_add(offset));
                len.filter(|&l| l <= bytes.len() as u64)
                    .map(|l| bytes[offset as usize..l as usize].to_vec())
                    .ok_or_else(|| {
                        bad(format!(
                            "sparse {what}: {n} entries run past the end of bufferViews[{v}]"
                        ))
                    })
            };
            let isize = ict.0.size();
            let idx = slice(
                sparse.indices.buffer_view.value(),
                sparse.indices.byte_offset.0,
                isize,
                "indices",
            )?;
            let vals = slice(
                sparse.values.buffer_view.value(),
                sparse.values.byte_offset.0,
                elem,
                "values",
            )?;
            let mut last = None;
            for k in 0..n {
                let i = component(ict.0, &idx[k * isize..]) as usize;
                if i >= count || last.is_some_and(|l| i <= l) {
                    return Err(bad(format!(
                        "sparse index {k} = {i} is out of range or out of order (count {count})"
                    )));
                }
                last = Some(i);
                let mut values = Vec::with_capacity(dims);
                decode(&vals[k * elem..], &mut values);
                raw[i * dims..(i + 1) * dims].copy_from_slice(&values);
            }
        }
        Ok(Values { ty, dims, normalized: acc.normalized, raw })
    }

    /// Reads a float attribute of one of the accessor `types`: FLOAT components, or normalized
    /// integers when `normalized_ok`. Every value must be finite.
    pub fn floats(
        &self,
        a: usize,
        types: &[Type],
        normalized_ok: bool,
        usage: &str,
    ) -> Result<(usize, Vec<f32>)> {
        let v = self.read(a, usage)?;
        let element = format!("accessors[{a}]");
        let t = match self.root.accessors[a].type_ {
            Checked::Valid(t) => Some(t),
            Checked::Invalid => None,
        };
        if !t.is_some_and(|t| types.contains(&t)) {
            let want: Vec<&str> = types.iter().map(|&t| type_name(t)).collect();
            let got = t.map_or("?", type_name);
            return Err(err(
                self.path,
                element,
                format!("{usage} must be {}, is {got}", want.join(" or ")),
            ));
        }
        let scale = match (v.ty, v.normalized && normalized_ok) {
            (ComponentType::F32, _) => 1.0,
            (ComponentType::U8, true) => 1.0 / 255.0,
            (ComponentType::U16, true) => 1.0 / 65535.0,
            (ComponentType::I8, true) => 1.0 / 127.0,
            (ComponentType::I16, true) => 1.0 / 32767.0,
            (ty, _) => {
                let allowed = if normalized_ok { "FLOAT or normalized integers" } else { "FLOAT" };
                return Err(err(
                    self.path,
                    element,
                    format!(
                        "{usage} must be {allowed}, is {ty:?}{}",
                        if v.normalized { " (normalized)" } else { "" }
                    ),
                ));
            }
        };
        // Signed normalized integers map −128 and −32768 to −1, like −127 and −32767.
        let signed = scale != 1.0 && matches!(v.ty, ComponentType::I8 | ComponentType::I16);
        let out: Vec<f32> = v
            .raw
            .iter()
            .map(|&x| if signed { (x * scale).max(-1.0) } else { x * scale } as f32)
            .collect();
        if let Some(i) = out.iter().position(|x| !x.is_finite()) {
            let e = i / v.dims;
            let value = &out[e * v.dims..(e + 1) * v.dims];
            return Err(err(
                self.path,
                element,
                format!("element {e} of {usage} is not finite: {value:?}"),
            ));
        }
        Ok((v.dims, out))
    }

    /// Reads unsigned integers (indices, joints) of one of the accessor `types`, with one of the
    /// component types `allowed`, not normalized.
    pub fn uints(
        &self,
        a: usize,
        types: &[Type],
        allowed: &[ComponentType],
        usage: &str,
    ) -> Result<Vec<u32>> {
        let v = self.read(a, usage)?;
        let t = match self.root.accessors[a].type_ {
            Checked::Valid(t) => Some(t),
            Checked::Invalid => None,
        };
        if !t.is_some_and(|t| types.contains(&t)) || !allowed.contains(&v.ty) || v.normalized {
            let got = format!(
                "{} {:?}{}",
                t.map_or("?", type_name),
                v.ty,
                if v.normalized { " normalized" } else { "" }
            );
            let want: Vec<String> = allowed.iter().map(|c| format!("{c:?}")).collect();
            return Err(err(
                self.path,
                format!("accessors[{a}]"),
                format!("{usage} must be {} of {}, is {got}", type_name(types[0]), want.join("/")),
            ));
        }
        Ok(v.raw.iter().map(|&x| x as u32).collect())
    }
}
