//! The files a render will write, named before it starts: each must be free to write (not a
//! directory) and no two may share a name, or one would silently replace another (`--png
//! o.mask.png` beside `--aux`'s mask of `--out o.exr`).
use super::RenderArgs;
use anyhow::bail;
use std::path::{Path, PathBuf};

/// `out`'s sibling with `suffix` in place of its extension (`o.exr` → `o.mask.png`).
pub(super) fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "render".into());
    out.with_file_name(format!("{stem}{suffix}"))
}

/// The record beside the image (`o.exr` → `o.json`).
pub(super) fn json_path(out: &Path) -> PathBuf {
    out.with_extension("json")
}

/// Every file the render may write and what writes it: the image, its record, the preview,
/// and with `--aux` the light mask and each of the strategy's `aux_channels` as EXR and PNG.
fn planned(args: &RenderArgs, aux_channels: &[&str]) -> Vec<(PathBuf, String)> {
    let mut files = vec![
        (args.out.clone(), "--out".to_string()),
        (json_path(&args.out), "the render's record".to_string()),
    ];
    if let Some(p) = &args.png {
        files.push((p.clone(), "--png".to_string()));
    }
    if args.aux {
        files.push((
            sibling(&args.out, ".mask.png"),
            "--aux's light mask".to_string(),
        ));
        for name in aux_channels {
            for ext in ["exr", "png"] {
                let what = format!("--aux's `{name}` channel");
                files.push((sibling(&args.out, &format!(".{name}.{ext}")), what));
            }
        }
    }
    files
}

/// The name a path is written under, its directory made absolute (the directories exist:
/// `check_writable` has seen them), so that `o.png` and `./o.png` compare equal.
fn resolved(path: &Path) -> PathBuf {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    dir.join(path.file_name().unwrap_or_default())
}

/// Refuses a directory where `what` is to write a file.
pub(super) fn not_a_directory(path: &Path, what: &str) -> anyhow::Result<()> {
    if path.is_dir() {
        bail!(
            "{} ({what}) is a directory: name a file to write",
            path.display()
        );
    }
    Ok(())
}

/// Refuses, before the render, an output that is a directory or that two outputs share.
pub(super) fn check_planned(args: &RenderArgs, aux_channels: &[&str]) -> anyhow::Result<()> {
    let files = planned(args, aux_channels);
    for (i, (path, what)) in files.iter().enumerate() {
        not_a_directory(path, what)?;
        let name = resolved(path);
        if let Some((_, first)) = files[..i].iter().find(|(p, _)| resolved(p) == name) {
            bail!(
                "{} would be written twice, by {first} and by {what}: give --png (or --out) \
                 another name",
                path.display()
            );
        }
    }
    Ok(())
}
