use super::*;
use crate::report::Report;

/// Frame `i` of a small test animation: a gradient whose colours depend on the frame.
fn frame(i: u32, width: u32, height: u32) -> Srgb8Image {
    let pixels = (0..width * height)
        .map(|p| {
            let (x, y) = (p % width, p / width);
            [(x * 7 + i * 31) as u8, (y * 11 + i) as u8, (x ^ y ^ i) as u8]
        })
        .collect();
    Srgb8Image { width, height, pixels }
}

/// The big-endian `u32` at `at`.
fn be(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes(b[at..at + 4].try_into().unwrap())
}

#[test]
fn apng_decodes_to_the_frames_delay_and_pixels_written() {
    let frames: Vec<Srgb8Image> = (0..5).map(|i| frame(i, 37, 23)).collect();
    let anim = Animation::new(frames.clone(), 80).unwrap();
    let bytes = encode_apng(&anim).unwrap();
    let back = decode_apng(&bytes).unwrap();
    assert_eq!(back.frames.len(), 5);
    assert_eq!(back.size(), (37, 23));
    assert_eq!(back.frame_ms, 80);
    assert_eq!(
        back.frames[3].get(36, 22),
        [(36 * 7 + 3 * 31) as u8, (22 * 11 + 3) as u8, 36 ^ 22 ^ 3]
    );
    // Lossless: every pixel of every frame.
    assert_eq!(back.frames, frames);
    // The chunk layout of the APNG specification: signature, IHDR, acTL (5 frames, loop
    // forever), fcTL of frame 0 (37×23 at 0,0, delay 80/1000, dispose none, blend source).
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let actl = bytes.windows(4).position(|w| w == b"acTL").unwrap();
    assert_eq!((be(&bytes, actl - 4), be(&bytes, actl + 4), be(&bytes, actl + 8)), (8, 5, 0));
    let fctl = bytes.windows(4).position(|w| w == b"fcTL").unwrap();
    let f = fctl + 4;
    assert_eq!((be(&bytes, f), be(&bytes, f + 4), be(&bytes, f + 8)), (0, 37, 23));
    assert_eq!((be(&bytes, f + 12), be(&bytes, f + 16)), (0, 0));
    assert_eq!(bytes[f + 20..f + 26], [0, 80, 0x03, 0xE8, 0, 0]);
    assert!(fctl < bytes.windows(4).position(|w| w == b"IDAT").unwrap());
    assert_eq!(bytes.windows(4).filter(|w| w == b"fcTL").count(), 5);
    // A still-image reader (the image crate's) sees the first frame.
    let still = Srgb8Image::decode(&bytes, std::path::Path::new("<memory>")).unwrap();
    assert_eq!(still, frames[0]);
}

#[test]
fn one_frame_and_the_longest_delay_round_trip() {
    let anim = Animation::new(vec![frame(9, 1, 1)], u16::MAX).unwrap();
    let back = decode_apng(&encode_apng(&anim).unwrap()).unwrap();
    assert_eq!(back, anim);
}

#[test]
fn bad_animations_are_refused_before_anything_is_written() {
    let path = std::env::temp_dir().join(format!("voxlod-apng-{}.png", std::process::id()));
    std::fs::write(&path, b"old").unwrap();
    let mixed = Animation { frames: vec![frame(0, 8, 8), frame(1, 8, 9)], frame_ms: 100 };
    assert!(matches!(write_apng(&path, &mixed), Err(Error::SizeMismatch { b_height: 9, .. })));
    assert!(matches!(Animation::new(vec![], 100), Err(Error::InvalidParameter { .. })));
    assert!(matches!(Animation::new(vec![frame(0, 4, 4)], 0), Err(Error::InvalidParameter { .. })));
    let short = Srgb8Image { width: 4, height: 4, pixels: vec![[0; 3]; 15] };
    assert!(matches!(Animation::new(vec![short], 10), Err(Error::PixelCount { pixels: 15, .. })));
    let empty = Srgb8Image { width: 0, height: 3, pixels: vec![] };
    assert!(Animation::new(vec![empty], 10).is_err());
    // The old file is untouched.
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    let good = Animation::new(vec![frame(0, 3, 2), frame(1, 3, 2)], 40).unwrap();
    write_apng(&path, &good).unwrap();
    assert_eq!(decode_apng(&std::fs::read(&path).unwrap()).unwrap(), good);
    std::fs::remove_file(&path).unwrap();
    // Not a PNG, or a truncated one: an error naming the animation, no panic.
    let bytes = encode_apng(&good).unwrap();
    assert!(matches!(decode_apng(b"GIF89a"), Err(Error::Animation { .. })));
    for len in [0, 8, 40, bytes.len() / 2, bytes.len() - 13] {
        assert!(decode_apng(&bytes[..len]).is_err(), "truncated to {len}");
    }
}

#[test]
fn a_report_links_its_animation_and_lists_it_in_the_json() {
    let dir = std::env::temp_dir().join(format!("voxlod-apng-report-{}", std::process::id()));
    let anim = Animation::new((0..3).map(|i| frame(i, 16, 12)).collect(), 100).unwrap();
    let mut report = Report::new("turntable");
    report.heading(2, "scene").animation("spin", "a turn", anim.clone());
    let written = report.write(&dir).unwrap();
    let md = std::fs::read_to_string(&written.markdown).unwrap();
    assert!(md.contains("![a turn](assets/spin.png)"), "{md}");
    assert!(md.contains("3 frames of 16×12, 100 ms each"), "{md}");
    let back = decode_apng(&std::fs::read(dir.join("assets/spin.png")).unwrap()).unwrap();
    assert_eq!(back, anim);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&written.summary).unwrap()).unwrap();
    let a = &json["animations"][0];
    assert_eq!((a["file"].as_str(), a["frames"].as_u64()), (Some("assets/spin.png"), Some(3)));
    assert_eq!(a["section"].as_str(), Some("scene"));
    // The asset name shares the report's namespace: a plot of the same name is refused.
    report.plot("SPIN", crate::report::Plot::default());
    assert!(matches!(report.write(&dir), Err(Error::DuplicateAsset { .. })));
    std::fs::remove_dir_all(&dir).unwrap();
}
