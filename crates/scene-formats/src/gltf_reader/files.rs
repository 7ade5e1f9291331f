//! The files a glTF names: each must be a regular file, and its URI must decode.
use std::path::Path;

/// An error unless `path` is a regular file (reading a device or a pipe whole never ends); the
/// message does not name the file, the caller's error does.
pub(crate) fn regular_file(path: &Path) -> Result<(), String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if meta.is_file() {
        Ok(())
    } else {
        Err("not a regular file".into())
    }
}

/// The file an external glTF URI names (None for data URIs and unsupported schemes, which the
/// gltf crate refuses itself); relative URIs are percent-decoded and must be UTF-8.
pub(super) fn external_file(base: &Path, uri: &str) -> Result<Option<std::path::PathBuf>, String> {
    if uri.contains(':') {
        let file = uri
            .strip_prefix("file://")
            .or_else(|| uri.strip_prefix("file:"));
        return Ok(file.map(std::path::PathBuf::from));
    }
    let mut bytes = Vec::with_capacity(uri.len());
    let mut rest = uri.as_bytes();
    while let Some((&c, tail)) = rest.split_first() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (c, tail) {
            (b'%', [h, l, more @ ..]) if hex(*h).is_some() && hex(*l).is_some() => {
                bytes.push((hex(*h).unwrap_or(0) * 16 + hex(*l).unwrap_or(0)) as u8);
                rest = more;
            }
            _ => {
                bytes.push(c);
                rest = tail;
            }
        }
    }
    let decoded =
        String::from_utf8(bytes).map_err(|_| format!("URI `{uri}` does not decode to UTF-8"))?;
    Ok(Some(base.join(decoded)))
}
