//! Buffers: the GLB binary chunk, base64 data URIs, and files relative to the glTF read
//! through the resolver, each checked against its declared `byteLength`.

use std::io;
use std::path::Path;

use ::gltf::json;

use super::parse::err;
use crate::Result;

/// Decodes standard base64 (padding optional), naming the offset of a bad character.
pub(super) fn base64(text: &str) -> std::result::Result<Vec<u8>, String> {
    use ::base64::DecodeError;
    // The decoder checks the length before the alphabet: name a bad character first.
    let bad = text.bytes().position(|c| !(c.is_ascii_alphanumeric() || b"+/=".contains(&c)));
    if let Some(i) = bad {
        let c = text.as_bytes()[i] as char;
        return Err(format!("invalid base64 character {c:?} at offset {i}"));
    }
    ::base64::decode_config(text, ::base64::STANDARD).map_err(|e| match e {
        DecodeError::InvalidByte(i, c) | DecodeError::InvalidLastSymbol(i, c) => {
            format!("invalid base64 character {:?} at offset {i}", c as char)
        }
        DecodeError::InvalidLength => "truncated base64 (a lone final character)".into(),
    })
}

/// Decodes `%XX` escapes of a relative URI into a path.
fn percent_decode(uri: &str) -> std::result::Result<String, String> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
            let byte = hex.and_then(|h| u8::from_str_radix(h, 16).ok());
            out.push(byte.ok_or_else(|| format!("bad percent escape at offset {i} of '{uri}'"))?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("'{uri}' does not decode to UTF-8"))
}

/// Reads what a `uri` refers to: a base64 data URI, or a file relative to `base` read through
/// `resolve`. Returns the bytes and a description for messages.
pub(super) fn read_uri(
    uri: &str,
    base: &Path,
    resolve: &mut dyn FnMut(&Path) -> io::Result<Vec<u8>>,
) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest.split_once(',').ok_or("bad data URI: no ','")?;
        if !header.ends_with(";base64") {
            return Err(format!("data URI '{header}' is not base64-encoded"));
        }
        return base64(payload).map_err(|e| format!("bad data URI: {e}"));
    }
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1 && s.bytes().all(|c| c.is_ascii_alphanumeric() || b"+.-".contains(&c))
    });
    if let Some(s) = scheme {
        return Err(format!(
            "URI scheme '{s}:' is not supported (only relative paths and data URIs)"
        ));
    }
    let file = base.join(percent_decode(uri)?);
    resolve(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// Loads every buffer, checking it holds at least `byteLength` bytes (and keeping exactly that
/// many, so that views are checked against the declared length).
pub(super) fn load_buffers(
    path: &Path,
    root: &json::Root,
    bin: Option<&[u8]>,
    resolve: &mut dyn FnMut(&Path) -> io::Result<Vec<u8>>,
) -> Result<Vec<Vec<u8>>> {
    let base = path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let element = format!("buffers[{i}]");
        let mut data = match (&buffer.uri, bin) {
            (Some(uri), _) => read_uri(uri, base, resolve).map_err(|e| err(path, &element, e))?,
            (None, Some(bin)) if i == 0 => bin.to_vec(),
            (None, _) => {
                return Err(err(path, &element, "has no uri and the file has no GLB binary chunk"));
            }
        };
        let want = usize::try_from(buffer.byte_length.0).unwrap_or(usize::MAX);
        if data.len() < want {
            return Err(err(
                path,
                &element,
                format!("holds {} bytes, but byteLength is {want}", data.len()),
            ));
        }
        data.truncate(want);
        out.push(data);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_and_names_bad_characters() {
        assert_eq!(base64("AAECAwQ=").unwrap(), vec![0, 1, 2, 3, 4]);
        assert_eq!(base64("AAECAwQ").unwrap(), vec![0, 1, 2, 3, 4]);
        assert_eq!(base64("TWFu").unwrap(), b"Man");
        assert!(base64("TW!u").unwrap_err().contains("'!' at offset 2"));
        assert!(base64("TWFuA").unwrap_err().contains("truncated"));
    }

    #[test]
    fn uris() {
        let mut files = |p: &Path| -> io::Result<Vec<u8>> {
            if p == Path::new("dir/a b.bin") {
                Ok(vec![7])
            } else {
                Err(io::ErrorKind::NotFound.into())
            }
        };
        assert_eq!(read_uri("a%20b.bin", Path::new("dir"), &mut files).unwrap(), vec![7]);
        assert!(
            read_uri("missing.bin", Path::new("dir"), &mut files)
                .unwrap_err()
                .contains("dir/missing.bin")
        );
        assert!(
            read_uri("http://x/y.bin", Path::new("dir"), &mut files)
                .unwrap_err()
                .contains("'http:'")
        );
        assert!(
            read_uri("data:application/octet-stream,AAAA", Path::new(""), &mut files)
                .unwrap_err()
                .contains("not base64")
        );
        assert!(read_uri("a%2", Path::new(""), &mut files).unwrap_err().contains("percent escape"));
        assert_eq!(read_uri("data:;base64,AAE=", Path::new(""), &mut files).unwrap(), vec![0, 1]);
    }
}
