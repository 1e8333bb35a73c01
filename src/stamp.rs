//! The model's version, and the stamp that every doc and figure written from the model carries.
//!
//! [`MODEL_VERSION`] names the model's numbers: it changes whenever an output of the model changes (a new default, a
//! corrected constant, a different transport), not when code is only reorganised. A script that writes a doc or a
//! figure from the model stamps it ([`markdown_stamp`] for a Markdown file, [`stamp_png`] for a picture); the doc
//! test (tests/physics/doc_stamps.rs) fails when a stamp names an older version, so a figure cannot silently outlive
//! the model that made it. A change detector (tests/physics/model_version.rs) fails when the numbers change without
//! the version, and tells what to bump and regenerate (docs/tests.md, Stamped docs).

use std::path::Path;

use crate::error::SkinError;

/// The model's version: raised by one whenever the model's numbers change (see the module's documentation).
pub const MODEL_VERSION: u32 = 1;

/// The key of the PNG text chunk that carries a figure's stamp.
pub const PNG_STAMP_KEY: &str = "spectral-skin-model";

/// The marker every stamp starts with, in Markdown and in a PNG's text chunk.
const STAMP_PREFIX: &str = "spectral-skin model ";

/// The stamp of a doc written by `command` from this model: an HTML comment, invisible when rendered, to be put on
/// the doc's first lines (or above the block the command writes).
pub fn markdown_stamp(command: &str) -> String {
    format!("<!-- {STAMP_PREFIX}{MODEL_VERSION}: written by `{command}`; do not edit by hand -->")
}

/// `text` with its generated block `name` replaced: the lines from the one holding `<!-- BEGIN name -->` to the one
/// holding `<!-- END name -->` become those two markers around [`markdown_stamp`]`(command)` and `body`. For a doc
/// written partly by hand (README.md's list of maps, a table in a guide); a doc written whole starts with the stamp.
pub fn replace_markdown_block(text: &str, name: &str, command: &str, body: &str) -> Result<String, SkinError> {
    let (begin, end) = (format!("<!-- BEGIN {name} -->"), format!("<!-- END {name} -->"));
    let missing = |marker: &str| SkinError::invalid("doc block", format!("no line {marker:?} in the doc"));
    let start = text.find(&begin).ok_or_else(|| missing(&begin))?;
    let stop = start + text[start..].find(&end).ok_or_else(|| missing(&end))? + end.len();
    let body = body.trim_end_matches('\n');
    let stamp = markdown_stamp(command);
    Ok(format!("{}{begin}\n{stamp}\n{body}\n{end}{}", &text[..start], &text[stop..]))
}

/// Replaces the blocks `(name, body)` of the Markdown doc at `path` ([`replace_markdown_block`], each under the stamp
/// of `command`) and writes it back in one atomic write (staged beside it and renamed: never half a doc). A missing
/// marker leaves the doc as it was.
pub fn write_markdown_blocks(path: &Path, command: &str, blocks: &[(&str, &str)]) -> Result<(), SkinError> {
    let mut text =
        std::fs::read_to_string(path).map_err(|e| SkinError::io_caused(path, format!("cannot read: {e}"), e))?;
    for (name, body) in blocks {
        text = replace_markdown_block(&text, name, command, body)?;
    }
    crate::maps::io::write_atomic(path, text.as_bytes())
}

/// The model versions of every stamp in a Markdown text, in order of appearance (empty when it has none). A stamp
/// whose version does not parse is returned as `None`.
pub fn markdown_stamp_versions(text: &str) -> Vec<Option<u32>> {
    let marker = format!("<!-- {STAMP_PREFIX}");
    text.match_indices(&marker).map(|(at, _)| parse_version(&text[at + marker.len()..])).collect()
}

/// The version at the start of `rest` ("7: written by ..." gives 7).
fn parse_version(rest: &str) -> Option<u32> {
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    digits.parse().ok()
}

/// Stamps the PNG at `path` with this model's version and the command that wrote it (a tEXt chunk under
/// [`PNG_STAMP_KEY`]); the pixels are unchanged. Written to a temporary file beside it and renamed.
pub fn stamp_png(path: &Path, command: &str) -> Result<(), SkinError> {
    let io = |e: std::io::Error| SkinError::io_caused(path, format!("cannot stamp: {e}"), e);
    let png = |e: &dyn std::fmt::Display| SkinError::io(path, format!("not a PNG this can stamp: {e}"));
    let mut decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).map_err(io)?));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().map_err(|e| png(&e))?;
    let mut pixels = vec![0; reader.output_buffer_size().ok_or_else(|| png(&"image too large"))?];
    let frame = reader.next_frame(&mut pixels).map_err(|e| png(&e))?;
    let info = reader.info();
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, frame.width, frame.height);
        encoder.set_color(frame.color_type);
        encoder.set_depth(frame.bit_depth);
        if let Some(gamma) = info.source_gamma {
            encoder.set_source_gamma(gamma);
        }
        if let Some(srgb) = info.srgb {
            encoder.set_source_srgb(srgb);
        }
        encoder.set_compression(png::Compression::High);
        let text = format!("{STAMP_PREFIX}{MODEL_VERSION}: written by {command}");
        encoder.add_text_chunk(PNG_STAMP_KEY.to_string(), text).map_err(|e| png(&e))?;
        let mut writer = encoder.write_header().map_err(|e| png(&e))?;
        writer.write_image_data(&pixels[..frame.buffer_size()]).map_err(|e| png(&e))?;
        writer.finish().map_err(|e| png(&e))?;
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut staged = tempfile::NamedTempFile::new_in(dir).map_err(io)?;
    std::io::Write::write_all(&mut staged, &bytes).map_err(io)?;
    // The picture keeps its permissions (a temporary file is private to its owner).
    let permissions = std::fs::metadata(path).map_err(io)?.permissions();
    std::fs::set_permissions(staged.path(), permissions).map_err(io)?;
    staged.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}

/// The model version a PNG's stamp names: `Ok(None)` when it carries no stamp (or one that does not parse).
pub fn png_stamp_version(path: &Path) -> Result<Option<u32>, SkinError> {
    let file = std::fs::File::open(path).map_err(|e| SkinError::io_caused(path, format!("cannot read: {e}"), e))?;
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .map_err(|e| SkinError::io(path, format!("not a PNG: {e}")))?;
    let stamp = reader.info().uncompressed_latin1_text.iter().find(|chunk| chunk.keyword == PNG_STAMP_KEY);
    Ok(stamp.and_then(|chunk| chunk.text.strip_prefix(STAMP_PREFIX)).and_then(parse_version))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_markdown_stamp_reads_back_as_this_version() {
        let doc = format!("{}\n# A doc\n\ntext <!-- other comment -->\n", markdown_stamp("cargo run --example x"));
        assert_eq!(markdown_stamp_versions(&doc), vec![Some(MODEL_VERSION)]);
        assert_eq!(markdown_stamp_versions("<!-- spectral-skin model x: written -->"), vec![None]);
        assert!(markdown_stamp_versions("# no stamp").is_empty());
    }

    #[test]
    fn a_block_is_replaced_between_its_markers_and_stamped() {
        let doc = "# Doc\n\n<!-- BEGIN maps -->\nold\nlines\n<!-- END maps -->\n\nafter\n";
        let new = replace_markdown_block(doc, "maps", "a script", "new\n").unwrap();
        let expected =
            format!("# Doc\n\n<!-- BEGIN maps -->\n{}\nnew\n<!-- END maps -->\n\nafter\n", markdown_stamp("a script"));
        assert_eq!(new, expected);
        assert_eq!(replace_markdown_block(&new, "maps", "a script", "new").unwrap(), new);
        let err = replace_markdown_block(doc, "palette", "a script", "x").unwrap_err().to_string();
        assert!(err.contains("BEGIN palette"), "{err}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("doc.md");
        std::fs::write(&path, doc).unwrap();
        write_markdown_blocks(&path, "a script", &[("maps", "new\n")]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), expected);
        assert!(write_markdown_blocks(&path, "a script", &[("maps", "other"), ("palette", "x")]).is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), expected, "a missing marker changed the doc");
    }

    #[test]
    fn a_stamped_png_keeps_its_pixels_and_reads_back_as_this_version() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("figure.png");
        let pixels: Vec<u8> = (0..4 * 3 * 3).map(|i| (i * 7) as u8).collect();
        image::save_buffer(&path, &pixels, 4, 3, image::ColorType::Rgb8).unwrap();
        assert_eq!(png_stamp_version(&path).unwrap(), None);
        stamp_png(&path, "a test").unwrap();
        assert_eq!(png_stamp_version(&path).unwrap(), Some(MODEL_VERSION));
        assert_eq!(image::open(&path).unwrap().to_rgb8().into_raw(), pixels);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).unwrap();
            stamp_png(&path, "again").unwrap();
            assert_eq!(std::fs::metadata(&path).unwrap().permissions().mode() & 0o777, 0o644);
        }
        let not_png = dir.path().join("x.png");
        std::fs::write(&not_png, b"text").unwrap();
        assert!(stamp_png(&not_png, "a test").is_err());
    }
}
