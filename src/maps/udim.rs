//! UDIM tile sets: one texture made of tiles, each a file whose name carries its tile number (`face.1001.exr`,
//! `face.1002.exr`, ...), named together with the token `<UDIM>` (`face.<UDIM>.exr`), as Blender, Mari and Substance
//! name them. A tile's number is 1001 + u + 10 v for the tile at column u (0..9) and row v of UV space.
//!
//! The maps of a tile set are computed as one texture: the tiles are stacked (same width) so that one decision (which
//! parameters vary, one table, a specular map or a constant) covers every tile, and each output is written as a tile
//! set with the same tiles (`albedo.1001.exr`, ...).

use std::path::{Path, PathBuf};

use super::io::{ParamInputs, ParamSource};
use crate::error::SkinError;

/// The token that stands for the tile number in a file name.
pub const UDIM_TOKEN: &str = "<UDIM>";
/// The tile numbers a tile set may hold: 1001 (u 0..1, v 0..1) to 2000 (ten columns, a hundred rows).
pub const TILE_RANGE: std::ops::RangeInclusive<u32> = 1001..=2000;

/// Whether `path`'s file name holds [`UDIM_TOKEN`].
pub fn is_tile_set(path: &Path) -> bool {
    path.file_name().is_some_and(|n| n.to_string_lossy().contains(UDIM_TOKEN))
}

/// `tile` as a UDIM tile number: in [`TILE_RANGE`], else an error naming `name` (the argument) and the range.
pub fn check_tile(name: &str, tile: i64) -> Result<u32, SkinError> {
    u32::try_from(tile).ok().filter(|t| TILE_RANGE.contains(t)).ok_or_else(|| {
        SkinError::invalid(
            name,
            format!("must be a UDIM tile, {} to {}; got {tile}", TILE_RANGE.start(), TILE_RANGE.end()),
        )
    })
}

/// A UDIM tile set stacked top to bottom in one image `height` rows high, as a caller gives it: (tile, rows) pairs in
/// stacking order. Returns the [`TileRows`] (tile, first row, rows) of each; an error names `name` (the argument),
/// what is wrong and what is expected: each tile in [`TILE_RANGE`] and given once, each at least one row, the rows
/// adding up to `height`.
pub fn stacked_tile_rows(name: &str, tiles: &[(i64, i64)], height: usize) -> Result<TileRows, SkinError> {
    let wrong = |problem: String| {
        let pairs: Vec<String> = tiles.iter().map(|(t, r)| format!("({t}, {r})")).collect();
        SkinError::invalid(
            name,
            format!(
                "{problem}: expected (tile, rows) pairs stacked top to bottom, each tile a UDIM tile {} to {} given \
                 once with at least one row, the rows adding up to the image's {height}; got [{}]",
                TILE_RANGE.start(),
                TILE_RANGE.end(),
                pairs.join(", ")
            ),
        )
    };
    let mut rows: TileRows = Vec::with_capacity(tiles.len());
    let mut first = 0usize;
    for &(tile, count) in tiles {
        let Ok(number) = check_tile(name, tile) else {
            return Err(wrong(format!("tile {tile} is not a UDIM tile")));
        };
        if rows.iter().any(|r| r.0 == number) {
            return Err(wrong(format!("tile {tile} is given twice")));
        }
        let Some(count) = usize::try_from(count).ok().filter(|&n| n > 0) else {
            return Err(wrong(format!("tile {tile} has {count} rows")));
        };
        rows.push((number, first, count));
        first = first.saturating_add(count);
    }
    if first != height {
        return Err(wrong(format!("the rows add up to {first}")));
    }
    Ok(rows)
}

/// `pattern` with [`UDIM_TOKEN`] in its file name replaced by `tile` (a path without the token is returned as it is).
pub fn tile_path(pattern: &Path, tile: u32) -> PathBuf {
    match pattern.file_name() {
        Some(name) if is_tile_set(pattern) => {
            pattern.with_file_name(name.to_string_lossy().replacen(UDIM_TOKEN, &tile.to_string(), 1))
        }
        _ => pattern.to_path_buf(),
    }
}

/// The name of a tile's output file: `albedo.exr` for tile 1001 is `albedo.1001.exr` (Blender's `<UDIM>` form).
pub fn tile_file_name(file: &str, tile: u32) -> String {
    match file.rsplit_once('.') {
        Some((stem, extension)) => format!("{stem}.{tile}.{extension}"),
        None => format!("{file}.{tile}"),
    }
}

/// The name of a tile set of outputs: `albedo.exr` -> `albedo.<UDIM>.exr`.
pub fn tile_set_file_name(file: &str) -> String {
    match file.rsplit_once('.') {
        Some((stem, extension)) => format!("{stem}.{UDIM_TOKEN}.{extension}"),
        None => format!("{file}.{UDIM_TOKEN}"),
    }
}

/// The tiles of a tile set on disk: every file in `pattern`'s folder whose name is `pattern`'s with four digits of
/// [`TILE_RANGE`] for the token, sorted. An error names the folder and the pattern when there are none.
pub fn find_tiles(pattern: &Path) -> Result<Vec<u32>, SkinError> {
    let name = pattern.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let Some((before, after)) = name.split_once(UDIM_TOKEN) else {
        return Err(SkinError::invalid(
            "tile set",
            format!("{}: the file name has no {UDIM_TOKEN}", pattern.display()),
        ));
    };
    let folder = match pattern.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let entries = std::fs::read_dir(folder)
        .map_err(|e| SkinError::io_caused(folder, format!("cannot list the folder of the tile set {name}: {e}"), e))?;
    let mut tiles: Vec<u32> = entries
        .filter_map(|entry| {
            let file = entry.ok()?.file_name().to_string_lossy().into_owned();
            let digits = file.strip_prefix(before)?.strip_suffix(after)?;
            let tile: u32 = if digits.len() == 4 && digits.bytes().all(|b| b.is_ascii_digit()) {
                digits.parse().ok()?
            } else {
                return None;
            };
            TILE_RANGE.contains(&tile).then_some(tile)
        })
        .collect();
    tiles.sort_unstable();
    if tiles.is_empty() {
        return Err(SkinError::io(
            folder,
            format!(
                "no tiles of {name}: expected files named {before}NNNN{after} with NNNN a tile number {} to {}",
                TILE_RANGE.start(),
                TILE_RANGE.end()
            ),
        ));
    }
    Ok(tiles)
}

impl ParamInputs {
    /// The first file of these inputs whose name holds [`UDIM_TOKEN`] (the tile set that decides the tiles).
    pub fn tile_set(&self) -> Option<&Path> {
        self.files().into_iter().find(|p| is_tile_set(p))
    }

    /// Every file these inputs name.
    fn files(&self) -> Vec<&Path> {
        fn source(s: &ParamSource) -> Option<&Path> {
            match s {
                ParamSource::File(p) => Some(p.as_path()),
                ParamSource::Constant(_) => None,
            }
        }
        match self {
            ParamInputs::Multi { path, .. } => vec![path.as_path()],
            ParamInputs::Separate(sources) => sources.iter().filter_map(source).collect(),
            ParamInputs::Extended { inputs, extended } => {
                let mut files = inputs.files();
                files.extend(extended.iter().flatten().filter_map(source));
                files
            }
        }
    }

    /// These inputs for one tile: every file name's [`UDIM_TOKEN`] replaced by `tile` (files without it are used for
    /// every tile).
    pub fn for_tile(&self, tile: u32) -> ParamInputs {
        let source = |s: &ParamSource| match s {
            ParamSource::File(p) => ParamSource::File(tile_path(p, tile)),
            ParamSource::Constant(v) => ParamSource::Constant(*v),
        };
        match self {
            ParamInputs::Multi { path, constants } => {
                ParamInputs::Multi { path: tile_path(path, tile), constants: *constants }
            }
            ParamInputs::Separate(sources) => ParamInputs::Separate(sources.each_ref().map(source)),
            ParamInputs::Extended { inputs, extended } => ParamInputs::Extended {
                inputs: Box::new(inputs.for_tile(tile)),
                extended: extended.each_ref().map(|e| e.as_ref().map(source)),
            },
        }
    }
}

/// Tiles stacked into one image, top to bottom in tile order: `(tile, first row, rows)` of each.
pub type TileRows = Vec<(u32, usize, usize)>;

/// Check that the tiles of a set (`sizes`: each tile's width and height, in `tiles` order) can be computed as one
/// texture: one width (an error names the first tile whose width differs). Each tile was read within the texel limit
/// (`check_texel_count`); the set has none of its own, as its tiles are computed and written one at a time.
pub fn check_tile_widths(tiles: &[u32], sizes: &[(usize, usize)]) -> Result<(), SkinError> {
    let width = sizes.first().map_or(0, |s| s.0);
    if let Some((t, s)) = tiles.iter().zip(sizes).find(|(_, s)| s.0 != width) {
        return Err(SkinError::invalid(
            "tile set",
            format!(
                "the tiles must have one width to be computed as one texture: tile {} is {} wide, tile {t} is {} wide \
                 (resize the tiles, or compute each tile alone)",
                tiles[0], width, s.0
            ),
        ));
    }
    Ok(())
}
