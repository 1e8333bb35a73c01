//! Docs that cannot go stale: every figure, table and picture README.md and docs/ show from the model is written by
//! a script that stamps it with the model's version (src/stamp.rs), and here each stamp must name the current
//! `MODEL_VERSION`. When the model's numbers change (model_version.rs makes that visible), this fails and names the
//! command that regenerates each stale doc (docs/tests.md, Stamped docs).

use std::path::{Path, PathBuf};

use spectral_skin::stamp::{markdown_stamp_versions, png_stamp_version};
use spectral_skin::MODEL_VERSION;

/// The docs whose numbers come from the model, each written (whole or in stamped blocks) by a script. A doc not
/// listed here may still carry stamps, which are checked all the same.
const MODEL_DOCS: &[&str] = &[
    "README.md",
    "docs/accuracy-vs-time.md",
    "docs/blender-principled.md",
    "docs/blender-targets.md",
    "docs/lookdev.md",
    "docs/measured-skin.md",
    "docs/model.md",
    "docs/scene-effects.md",
    "docs/shader-table.md",
    "docs/skin-atlas.md",
    "docs/surface-slices.md",
];

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![repo().join("README.md")];
    files.extend(files_with_extension(&repo().join("docs"), "md"));
    files
}

fn files_with_extension(dir: &Path, extension: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            found.extend(files_with_extension(&path, extension));
        } else if path.extension().is_some_and(|e| e == extension) {
            found.push(path);
        }
    }
    found.sort();
    found
}

/// The command a doc's stamps name (for the message): the text between the first stamp's backquotes.
fn regenerating_command(text: &str) -> &str {
    text.split("<!-- spectral-skin model ").nth(1).and_then(|s| s.split('`').nth(1)).unwrap_or("(unnamed)")
}

#[test]
fn every_stamp_in_the_docs_names_the_current_model() {
    let mut stale = Vec::new();
    for path in markdown_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        let versions = markdown_stamp_versions(&text);
        if versions.iter().any(|v| *v != Some(MODEL_VERSION)) {
            stale.push(format!("{} ({:?}): rerun {}", path.display(), versions, regenerating_command(&text)));
        }
    }
    assert!(stale.is_empty(), "docs stamped with another model than {MODEL_VERSION}:\n{}", stale.join("\n"));
}

#[test]
fn every_model_doc_is_stamped() {
    let unstamped: Vec<&str> = MODEL_DOCS
        .iter()
        .copied()
        .filter(|doc| markdown_stamp_versions(&std::fs::read_to_string(repo().join(doc)).unwrap()).is_empty())
        .collect();
    assert!(
        unstamped.is_empty(),
        "docs with the model's numbers but no stamp (not written by a script?): {unstamped:?}"
    );
}

#[test]
fn every_picture_in_the_docs_is_stamped_with_the_current_model() {
    let pictures = files_with_extension(&repo().join("docs").join("images"), "png");
    assert!(pictures.len() >= 10, "docs/images has {} pictures", pictures.len());
    let stale: Vec<String> = pictures
        .iter()
        .filter_map(|path| match png_stamp_version(path).unwrap() {
            Some(v) if v == MODEL_VERSION => None,
            found => Some(format!("{}: {found:?}", path.display())),
        })
        .collect();
    assert!(
        stale.is_empty(),
        "pictures not stamped with model {MODEL_VERSION} (regenerate them):\n{}",
        stale.join("\n")
    );
}

#[test]
fn every_picture_a_doc_shows_exists() {
    let mut missing = Vec::new();
    for path in markdown_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        for link in text.split("](").skip(1).filter_map(|s| s.split(')').next()).filter(|l| l.ends_with(".png")) {
            if !path.parent().unwrap().join(link).exists() {
                missing.push(format!("{}: {link}", path.display()));
            }
        }
    }
    assert!(missing.is_empty(), "pictures the docs show that are not there: {missing:?}");
}
