//! Writing maps to files from Python: how a write lays rows out in files (one image, one UDIM tile, a stacked tile
//! set), the images of a result checked and borrowed (or gathered) as row-major texels, and the one call of the
//! core's writer (staged, then committed together) with the GIL released.

use std::path::Path;

use numpy::{PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyKeyError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use crate::maps::io::{Compression, ExrOptions, Precision};
use crate::maps::kinds::{MapKind, ALBEDO_MAP, MAP_KINDS, RADIUS_MAP};
use crate::maps::output::{check_prefix, commit_map_files, output_name, stage_map_files, tile_output_name, MapFiles};
use crate::maps::udim::{check_tile, stacked_tile_rows, tile_set_file_name, TileRows};

use super::args::named;
use super::convert::{float_array, shape_text, type_name, FloatArray};
use super::detach::detached;
use super::errors::{internal, invalid};

/// How a write lays the rows out in files.
pub(super) enum Tiling {
    /// One image: the untiled files, or (`Some`) the files of that one UDIM tile.
    One(Option<u32>),
    /// A UDIM tile set stacked top to bottom: each tile's rows its own files.
    Set(TileRows),
}

impl Tiling {
    /// From `tile` (write_maps' one tile) and `tiles` (a stacked tile set of an image `height` rows high).
    pub(super) fn of(tile: Option<i64>, tiles: Option<Vec<(i64, i64)>>, height: usize) -> PyResult<Tiling> {
        Ok(match (tile, tiles) {
            (Some(_), Some(_)) => {
                return Err(invalid("tiles", "give tile (one tile's image) or tiles (a stacked tile set), not both"))
            }
            (Some(t), None) => Tiling::One(Some(check_tile("tile", t)?)),
            (None, Some(t)) => Tiling::Set(stacked_tile_rows("tiles", &t, height)?),
            (None, None) => Tiling::One(None),
        })
    }
}

/// The EXR options of a write, after checking the prefix.
pub(super) fn write_options(prefix: Option<&str>, precision: &str, compression: &str) -> PyResult<ExrOptions> {
    let exr = ExrOptions { precision: named::<Precision>(precision)?, compression: named::<Compression>(compression)? };
    check_prefix(prefix)?;
    Ok(exr)
}

/// The maps one write puts in files, row-major float32 texels: (H, W, 3) interleaved Base Color and radius, (H, W)
/// surface maps (Specular IOR Level, Coat Weight, Coat Roughness). Borrowed: from a [`MapsPy`]'s arrays, or from (or
/// gathered out of) the arrays given to `write_maps`.
pub(super) struct MapImages<'a> {
    height: usize,
    width: usize,
    base_color: Option<&'a [f32]>,
    radius_mm: Option<&'a [f32]>,
    surface: Vec<(MapKind, &'a [f32])>,
}

impl<'a> MapImages<'a> {
    /// The images, each checked to hold (H, W, channels) values.
    pub(super) fn new(
        height: usize,
        width: usize,
        base_color: Option<&'a [f32]>,
        radius_mm: Option<&'a [f32]>,
        surface: Vec<(MapKind, &'a [f32])>,
    ) -> PyResult<Self> {
        let sized = [(base_color, 3), (radius_mm, 3)].into_iter().chain(surface.iter().map(|&(_, s)| (Some(s), 1)));
        for (texels, channels) in sized {
            if texels.is_some_and(|t| t.len() != height * width * channels) {
                return Err(internal("an image whose size is not its shape's"));
            }
        }
        Ok(MapImages { height, width, base_color, radius_mm, surface })
    }
}

/// Interleaved RGB rows (`width` texels each) to three planes, rows in parallel.
fn deinterleave(width: usize, texels: &[f32]) -> [Vec<f32>; 3] {
    let n = texels.len() / 3;
    let (mut p0, mut p1, mut p2) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
    p0.par_chunks_mut(width)
        .zip(p1.par_chunks_mut(width))
        .zip(p2.par_chunks_mut(width))
        .zip(texels.par_chunks(3 * width))
        .for_each(|(((r0, r1), r2), row)| {
            for (x, texel) in row.chunks_exact(3).enumerate() {
                r0[x] = texel[0];
                r1[x] = texel[1];
                r2[x] = texel[2];
            }
        });
    [p0, p1, p2]
}

/// Write `images` as laid out by `tiling` with the core's writer, the GIL released: every file of every tile
/// staged, then all committed together ([`commit_map_files`], which also removes this prefix's files of those tiles
/// that this write did not write). Returns {"albedo" | "radius" | "specular": path} of the maps written (for a tile
/// set, the path with `<UDIM>`).
pub(super) fn write_images<'py>(
    py: Python<'py>,
    images: &MapImages<'_>,
    folder: &Path,
    prefix: Option<&str>,
    exr: ExrOptions,
    tiling: Tiling,
) -> PyResult<Bound<'py, PyDict>> {
    let parts: Vec<(Option<u32>, usize, usize)> = match &tiling {
        Tiling::One(tile) => vec![(*tile, 0, images.height)],
        Tiling::Set(rows) => rows.iter().map(|&(tile, first, rows)| (Some(tile), first, rows)).collect(),
    };
    detached(py, || {
        let w = images.width;
        let mut staged = Vec::new();
        for &(tile, first, rows) in &parts {
            // One tile's planes at a time: the writer reads planes; they are dropped once the tile is staged.
            let rgb =
                |texels: Option<&[f32]>| texels.map(|t| deinterleave(w, &t[3 * w * first..3 * w * (first + rows)]));
            let (base_color, radius_mm) = (rgb(images.base_color), rgb(images.radius_mm));
            let files = MapFiles {
                width: w,
                height: rows,
                base_color: base_color.as_ref(),
                radius_mm: radius_mm.as_ref(),
                surface: images.surface.iter().map(|&(k, s)| (k, &s[w * first..w * (first + rows)])).collect(),
            };
            staged.extend(stage_map_files(folder, prefix, tile, &files, exr)?);
        }
        let tiles: Vec<Option<u32>> = parts.iter().map(|p| p.0).collect();
        commit_map_files(folder, prefix, &tiles, staged)
    })?;
    let dict = PyDict::new(py);
    for kind in &MAP_KINDS {
        let (key, file) = (kind.name, kind.file);
        let present = match key {
            k if k == ALBEDO_MAP.name => images.base_color.is_some(),
            k if k == RADIUS_MAP.name => images.radius_mm.is_some(),
            k => images.surface.iter().any(|(s, _)| s.name == k),
        };
        if present {
            let name = match &tiling {
                Tiling::One(tile) => tile_output_name(prefix, *tile, file),
                Tiling::Set(_) => tile_set_file_name(&output_name(prefix, file)),
            };
            dict.set_item(key, folder.join(name))?;
        }
    }
    Ok(dict)
}

/// An image of `write_maps`' result: its size and its channels as row-major planes.
pub(super) struct ResultImage {
    pub(super) height: usize,
    pub(super) width: usize,
    pub(super) planes: Vec<Vec<f32>>,
}

/// One image of a result mapping, checked: a float array of `channels` channels ((H, W, channels), or (H, W) for
/// one channel), with its shape. None when the key is absent or None.
pub(super) fn result_array<'py>(
    result: &Bound<'py, PyAny>,
    key: &str,
    channels: usize,
) -> PyResult<Option<(FloatArray<'py>, Vec<usize>)>> {
    let obj = match result.get_item(key) {
        Ok(obj) if !obj.is_none() => obj,
        Ok(_) => return Ok(None),
        Err(e) if e.is_instance_of::<PyKeyError>(result.py()) => return Ok(None),
        Err(e) => return Err(e),
    };
    let (ndim, expected) = if channels == 1 {
        (2, "a float32 (H, W) numpy array".to_string())
    } else {
        (3, format!("a float32 (H, W, {channels}) numpy array"))
    };
    let name = format!("result[{key:?}]");
    let array = float_array(&name, &obj, ndim, &expected)?
        .ok_or_else(|| PyTypeError::new_err(format!("{name} must be {expected} or None; got {}", type_name(&obj))))?;
    let shape = array.shape();
    if channels > 1 && shape[2] != channels {
        return Err(invalid(name, format!("must be {expected}; got shape {}", shape_text(&shape))));
    }
    Ok(Some((array, shape)))
}

/// One image of `write_maps`' result as row-major planes: `channels` of them (an (H, W, channels) array, or (H, W)
/// for one channel). None when the key is absent or None.
pub(super) fn result_planes(result: &Bound<'_, PyAny>, key: &str, channels: usize) -> PyResult<Option<ResultImage>> {
    let Some((array, shape)) = result_array(result, key, channels)? else {
        return Ok(None);
    };
    let planes = if channels == 1 {
        vec![array.plane(None)?]
    } else {
        (0..channels).map(|c| array.plane(Some(c))).collect::<PyResult<_>>()?
    };
    Ok(Some(ResultImage { height: shape[0], width: shape[1], planes }))
}

/// The texels of an image given to `write_maps`, row-major: a read-only C-contiguous float32 array (a :func:`maps`
/// result's) is read in place; any other is gathered into a float32 copy first (under the GIL, so nothing can change
/// it while the GIL is released for the write).
pub(super) enum Texels<'py> {
    InPlace(PyReadonlyArrayDyn<'py, f32>),
    Copied(Vec<f32>),
}

impl<'py> Texels<'py> {
    pub(super) fn of(array: FloatArray<'py>) -> PyResult<Self> {
        let unreadable = |e: numpy::BorrowError| PyTypeError::new_err(format!("cannot read the array: {e}"));
        Ok(match array {
            FloatArray::F32(a) if a.is_c_contiguous() && !writeable(a.as_any())? => {
                Texels::InPlace(a.try_readonly().map_err(unreadable)?)
            }
            FloatArray::F32(a) => {
                Texels::Copied(a.try_readonly().map_err(unreadable)?.as_array().iter().copied().collect())
            }
            FloatArray::F64(a) => {
                Texels::Copied(a.try_readonly().map_err(unreadable)?.as_array().iter().map(|&v| v as f32).collect())
            }
        })
    }

    pub(super) fn as_slice(&self) -> PyResult<&[f32]> {
        match self {
            Texels::InPlace(a) => a.as_slice().map_err(internal),
            Texels::Copied(v) => Ok(v),
        }
    }
}

/// Whether numpy lets `array` be written into.
fn writeable(array: &Bound<'_, PyAny>) -> PyResult<bool> {
    array.getattr("flags")?.getattr("writeable")?.extract()
}
