//! Per-voxel record types the `.vxl` container can store: the [`VxlRecord`] trait, the
//! zero-sized [`Occupancy`] record, and the implementations for plain scalars and small arrays.
//! Also the byte-order conversion of a payload (a no-op on little-endian hosts).

/// A per-voxel record the `.vxl` container can store.
///
/// The file names the record type with [`VxlRecord::TAG`] and its size, so a reader refuses a
/// payload of another type. Records are stored field by field in little-endian order, whatever
/// the host: [`VxlRecord::FIELD_WIDTHS`] says how wide each scalar field is.
///
/// Implementing it for a record of your own (a `#[repr(C)]` Pod struct):
/// ```
/// use voxlod_format::vxl::VxlRecord;
/// #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
/// #[repr(C)]
/// struct Average {
///     colour: [f32; 3],
///     coverage: f32,
/// }
/// impl VxlRecord for Average {
///     const TAG: [u8; 4] = *b"AVG1";
///     const FIELD_WIDTHS: &'static [u8] = &[4]; // four f32, each 4 bytes wide
/// }
/// ```
pub trait VxlRecord: bytemuck::Pod {
    /// Four bytes naming the record type in files (printable ASCII by convention; a new layout
    /// of the same data gets a new tag).
    const TAG: [u8; 4];
    /// Widths in bytes (1, 2, 4 or 8) of the record's scalar fields in memory order; the
    /// pattern repeats until it fills the record, so `[f32; 4]` is `&[4]` and a
    /// `{ u16, u8, u8 }` struct is `&[2, 1, 1]`. Empty for zero-sized records. Checked at
    /// compile time when a record type is written or read.
    const FIELD_WIDTHS: &'static [u8];
}

/// Occupancy alone: a zero-sized record, so an occupancy map's payload takes no bytes and its
/// brick masks carry all the information.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct Occupancy;

impl VxlRecord for Occupancy {
    const TAG: [u8; 4] = *b"occ ";
    const FIELD_WIDTHS: &'static [u8] = &[];
}

macro_rules! records {
    ($($t:ty => $tag:literal, $width:literal;)*) => {$(
        impl VxlRecord for $t {
            const TAG: [u8; 4] = *$tag;
            const FIELD_WIDTHS: &'static [u8] = &[$width];
        }
    )*};
}

records! {
    u8 => b"u8  ", 1;
    u16 => b"u16 ", 2;
    u32 => b"u32 ", 4;
    u64 => b"u64 ", 8;
    f32 => b"f32 ", 4;
    f64 => b"f64 ", 8;
    [u8; 4] => b"4u8 ", 1;
    [f32; 3] => b"3f32", 4;
    [f32; 4] => b"4f32", 4;
}

/// Whether `T`'s size and field widths describe a storable record: size fits a `u32`, and for
/// a non-empty record, widths in {1, 2, 4, 8} whose sum divides the size.
pub(crate) const fn layout_ok<T: VxlRecord>() -> bool {
    let size = size_of::<T>();
    if size > u32::MAX as usize {
        return false;
    }
    if size == 0 {
        return true;
    }
    let widths = T::FIELD_WIDTHS;
    let mut sum = 0usize;
    let mut i = 0;
    while i < widths.len() {
        let w = widths[i];
        if !matches!(w, 1 | 2 | 4 | 8) {
            return false;
        }
        sum += w as usize;
        i += 1;
    }
    sum > 0 && size.is_multiple_of(sum)
}

/// Converts a payload between little-endian (the file) and the host's order, in place. The
/// conversion is its own inverse. A no-op on little-endian hosts.
pub(crate) fn convert_le(bytes: &mut [u8], widths: &[u8]) {
    if cfg!(target_endian = "big") {
        swap_fields(bytes, widths);
    }
}

/// Reverses the bytes of every field: records are `widths` repeated. Trailing bytes that do
/// not fill a whole pattern are left alone (the layout check rules them out).
fn swap_fields(bytes: &mut [u8], widths: &[u8]) {
    let pattern: usize = widths.iter().map(|&w| w as usize).sum();
    if pattern == 0 {
        return;
    }
    for chunk in bytes.chunks_exact_mut(pattern) {
        let mut at = 0;
        for &w in widths {
            chunk[at..at + w as usize].reverse();
            at += w as usize;
        }
    }
}

/// A record tag for people: the ASCII text without trailing spaces if it is printable
/// (`"u32"`), its hex value otherwise (`"0x00ff1234"`).
pub fn tag_name(tag: [u8; 4]) -> String {
    if tag.iter().all(|b| (0x20..0x7f).contains(b)) {
        String::from_utf8_lossy(&tag).trim_end().to_owned()
    } else {
        format!("{:#010x}", u32::from_be_bytes(tag))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_records_have_valid_layouts_and_distinct_tags() {
        const OK: [bool; 10] = [
            layout_ok::<Occupancy>(),
            layout_ok::<u8>(),
            layout_ok::<u16>(),
            layout_ok::<u32>(),
            layout_ok::<u64>(),
            layout_ok::<f32>(),
            layout_ok::<f64>(),
            layout_ok::<[u8; 4]>(),
            layout_ok::<[f32; 3]>(),
            layout_ok::<[f32; 4]>(),
        ];
        assert!(OK.iter().all(|&ok| ok));
        let tags = [
            Occupancy::TAG,
            u8::TAG,
            u16::TAG,
            u32::TAG,
            u64::TAG,
            f32::TAG,
            f64::TAG,
            <[u8; 4]>::TAG,
            <[f32; 3]>::TAG,
            <[f32; 4]>::TAG,
        ];
        let unique: std::collections::BTreeSet<_> = tags.iter().collect();
        assert_eq!(unique.len(), tags.len());
        assert_eq!(size_of::<Occupancy>(), 0);
    }

    #[test]
    fn bad_layouts_are_refused() {
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        #[repr(C)]
        struct Odd([u8; 6]);
        impl VxlRecord for Odd {
            const TAG: [u8; 4] = *b"odd ";
            const FIELD_WIDTHS: &'static [u8] = &[4]; // 4 does not divide 6
        }
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        #[repr(C)]
        struct NoWidths(u32);
        impl VxlRecord for NoWidths {
            const TAG: [u8; 4] = *b"now ";
            const FIELD_WIDTHS: &'static [u8] = &[];
        }
        assert!(!layout_ok::<Odd>());
        assert!(!layout_ok::<NoWidths>());
    }

    #[test]
    fn field_swap_matches_big_endian_encoding_and_is_an_involution() {
        // A { u16, u8, u8 } record pattern repeated twice, then [u32] and [u64] patterns.
        let mut bytes = [1u8, 2, 3, 4, 5, 6, 7, 8];
        swap_fields(&mut bytes, &[2, 1, 1]);
        assert_eq!(bytes, [2, 1, 3, 4, 6, 5, 7, 8]);
        swap_fields(&mut bytes, &[2, 1, 1]);
        assert_eq!(bytes, [1, 2, 3, 4, 5, 6, 7, 8]);
        let v = [0x0102_0304u32, 0xa0b0_c0d0];
        let mut le: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        swap_fields(&mut le, &[4]);
        let be: Vec<u8> = v.iter().flat_map(|x| x.to_be_bytes()).collect();
        assert_eq!(le, be);
        let mut w = 0x0102_0304_0506_0708u64.to_le_bytes();
        swap_fields(&mut w, &[8]);
        assert_eq!(w, 0x0102_0304_0506_0708u64.to_be_bytes());
    }

    #[test]
    fn tag_names() {
        assert_eq!(tag_name(*b"u32 "), "u32");
        assert_eq!(tag_name(*b"4f32"), "4f32");
        assert_eq!(tag_name([0, 0xff, 0x12, 0x34]), "0x00ff1234");
    }
}
