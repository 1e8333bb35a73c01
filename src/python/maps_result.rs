//! The result of `maps` as Python sees it: the read-only `Maps` mapping of numpy arrays (made from the core's
//! planes without a copy), its specular constants and report, and the writing of a result (`Maps.write`,
//! `write_maps`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use numpy::ndarray::Array2;
use numpy::{PyArray, PyArray2, PyArray3, PyArrayMethods};
use pyo3::exceptions::PyKeyError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyIterator, PyList, PyString};

use crate::maps::io::ExrOptions;
use crate::maps::kinds::{MapKind, ALBEDO_MAP, MAP_KINDS, RADIUS_MAP, SURFACE_MAP_KINDS};
use crate::maps::report::{MapReport, SpecularOutput};
use crate::maps::udim::check_tile;
use crate::surface::principled::SpecularParams;

use super::convert::{rgb_image, to_py};
use super::errors::{internal, invalid};
use super::maps_write::{result_array, write_images, write_options, MapImages, Texels, Tiling};

/// The fields of `SpecularParams` that do not depend on the oiliness: what `maps` returns in "specular_constants"
/// when the oiliness varies (beside the per-texel maps), and for the `paper` surface its Coat (weight 0).
const SPECULAR_CONSTANTS: [&str; 5] = ["surface", "roughness", "ior", "coat_ior", "beckmann_m"];
/// The Coat fields that are one value under the `paper` surface (no Coat) even when the oiliness varies.
const PAPER_COAT_CONSTANTS: [&str; 2] = ["coat_weight", "coat_roughness"];

/// What `maps` computed, before it meets Python: Base Color and radius interleaved (H, W, 3), the specular output and
/// the report.
pub(super) struct Computed {
    pub(super) height: usize,
    pub(super) width: usize,
    pub(super) base_color: Option<Vec<f32>>,
    pub(super) radius_mm: Option<Vec<f32>>,
    pub(super) specular: Option<SpecularOutput>,
    pub(super) report: MapReport,
}

impl MapsPy {
    /// The result of `computed`, its arrays handed to numpy without a copy and frozen; the report's total time
    /// measured from `start`.
    pub(super) fn of(py: Python<'_>, computed: Computed, start: Instant) -> PyResult<MapsPy> {
        let (height, width) = (computed.height, computed.width);
        let rgb = |data: Option<Vec<f32>>| {
            data.map(|d| rgb_image(py, height, width, d).and_then(|a| frozen(a.as_any()).map(|()| a.unbind())))
                .transpose()
        };
        let (albedo, radius) = (rgb(computed.base_color)?, rgb(computed.radius_mm)?);
        let plane = |texels: Vec<f32>| -> PyResult<Py<PyArray2<f32>>> {
            let array =
                PyArray::from_owned_array(py, Array2::from_shape_vec((height, width), texels).map_err(internal)?);
            frozen(array.as_any())?;
            Ok(array.unbind())
        };
        let (surface, specular_constants) = match computed.specular {
            None => (Vec::new(), None),
            Some(SpecularOutput::Constant(constants)) => (Vec::new(), Some(constants)),
            Some(SpecularOutput::Map { specular_ior_level, coat, constants }) => {
                let [level, weight, roughness] = SURFACE_MAP_KINDS;
                let mut maps = vec![(level, plane(specular_ior_level)?)];
                if let Some(coat) = coat {
                    maps.push((weight, plane(coat.weight)?));
                    maps.push((roughness, plane(coat.roughness)?));
                }
                (maps, Some(constants))
            }
        };
        let mut report = computed.report;
        report.seconds.total = start.elapsed().as_secs_f64();
        Ok(MapsPy { height, width, albedo, radius, surface, specular_constants, report })
    }
}

/// Flag a numpy array the core made read-only. Its memory belongs to the core's container (no writeable buffer), so
/// numpy also refuses to make it (or a view of it) writeable again: the array is frozen.
fn frozen(array: &Bound<'_, PyAny>) -> PyResult<()> {
    array.getattr("flags")?.setattr("writeable", false)
}

/// The keys of a :func:`maps` result that are not maps, after the maps ([`MAP_KINDS`] order) in the order the result
/// lists those present.
const CONSTANTS_KEY: &str = "specular_constants";
const REPORT_KEY: &str = "report";

/// The result of :func:`maps`: the texture maps of the outputs asked for, the specular constants and the report.
/// Read-only: its arrays are flagged not writeable (numpy refuses writes into them; copy one with ``np.array(a)``
/// to change it) and ``specular_constants`` and ``report`` are new dicts on each access. Each map has one name,
/// the same as the output that asks for it and the file it is written to (``albedo`` -> ``albedo.exr``).
///
/// Attributes (None when the output was not asked for):
///     albedo: float32 (H, W, 3), Principled Base Color (see :func:`maps`).
///     radius: float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale, mm.
///     specular: float32 (H, W), Principled Specular IOR Level per texel; None also when the oiliness is one value
///         everywhere (``specular_constants`` then holds the level).
///     coat_weight, coat_roughness: float32 (H, W), Principled Coat Weight and Coat Roughness per texel (the
///         ``measured`` surface with varying oiliness); None otherwise (``specular_constants`` then holds them).
///     specular_constants: the specular inputs that are one value (dict; see :func:`maps`).
///     report: what was done (dict; see :func:`maps`).
///     shape: (H, W).
///
/// It reads like a dict: ``result["albedo"]``, ``"radius" in result``,
/// ``result.keys()`` (those present, in the order above: an output not asked for is absent), ``result.get(key)``,
/// ``result.items()``, ``len(result)``, iteration over the keys, ``dict(result)``; it is a
/// ``collections.abc.Mapping``.
///
/// ``write(folder)`` writes its maps as EXRs with the core's writer, straight from its arrays (see ``Maps.write``).
#[pyclass(frozen, mapping, name = "Maps", module = "spectral_skin")]
pub(super) struct MapsPy {
    height: usize,
    width: usize,
    albedo: Option<Py<PyArray3<f32>>>,
    radius: Option<Py<PyArray3<f32>>>,
    /// The single-channel surface maps ([`SURFACE_MAP_KINDS`]) present, in that order.
    surface: Vec<(MapKind, Py<PyArray2<f32>>)>,
    /// The specular constants; with the surface maps (the oiliness varies) only those of `SPECULAR_CONSTANTS`
    /// (and for `paper` its Coat's) are shown.
    specular_constants: Option<SpecularParams>,
    report: MapReport,
}

impl MapsPy {
    /// The value of `key`, or None when the result has no such key.
    fn item<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        Ok(if key == ALBEDO_MAP.name {
            self.albedo.as_ref().map(|a| a.bind(py).clone().into_any())
        } else if key == RADIUS_MAP.name {
            self.radius.as_ref().map(|a| a.bind(py).clone().into_any())
        } else if key == CONSTANTS_KEY {
            self.specular_dict(py)?
        } else if key == REPORT_KEY {
            Some(self.report_dict(py)?)
        } else {
            self.surface_map(py, key).map(Bound::into_any)
        })
    }

    /// The surface map named `key` (a [`SURFACE_MAP_KINDS`] name), if held.
    fn surface_map<'py>(&self, py: Python<'py>, key: &str) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface.iter().find(|(k, _)| k.name == key).map(|(_, a)| a.bind(py).clone())
    }

    /// The keys present: the maps in [`MAP_KINDS`] order, then "specular_constants" and "report".
    fn present(&self) -> Vec<&'static str> {
        let mut keys: Vec<&'static str> = MAP_KINDS
            .iter()
            .map(|k| k.name)
            .filter(|&name| match name {
                n if n == ALBEDO_MAP.name => self.albedo.is_some(),
                n if n == RADIUS_MAP.name => self.radius.is_some(),
                n => self.surface.iter().any(|(k, _)| k.name == n),
            })
            .collect();
        if self.specular_constants.is_some() {
            keys.push(CONSTANTS_KEY);
        }
        keys.push(REPORT_KEY);
        keys
    }

    fn specular_dict<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(constants) = &self.specular_constants else {
            return Ok(None);
        };
        let all = to_py(py, constants)?;
        if self.surface.is_empty() {
            return Ok(Some(all));
        }
        // Only the constants that do not depend on the oiliness (surface::principled::surface_inputs).
        let kept = PyDict::new(py);
        let paper_coat: &[&str] = if constants.surface.is_paper() { &PAPER_COAT_CONSTANTS } else { &[] };
        for key in SPECULAR_CONSTANTS.iter().chain(paper_coat) {
            kept.set_item(key, all.get_item(key)?)?;
        }
        Ok(Some(kept.into_any()))
    }

    fn report_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let report = to_py(py, &self.report)?;
        // JSON has no infinity: serde_json writes a semi-infinite dermis as null. Python floats do.
        report
            .get_item("request")?
            .get_item("model")?
            .set_item("dermis_thickness_mm", self.report.request.model.dermis_thickness_mm)?;
        Ok(report)
    }

    /// Write the held maps, borrowed from the arrays (read-only, C-contiguous float32: the core made them).
    fn write_as<'py>(
        &self,
        py: Python<'py>,
        folder: &Path,
        prefix: Option<&str>,
        exr: ExrOptions,
        tiling: Tiling,
    ) -> PyResult<Bound<'py, PyDict>> {
        let base_color = self.albedo.as_ref().map(|a| a.bind(py).try_readonly()).transpose().map_err(internal)?;
        let radius_mm = self.radius.as_ref().map(|a| a.bind(py).try_readonly()).transpose().map_err(internal)?;
        let surface: Vec<(MapKind, _)> = self
            .surface
            .iter()
            .map(|(k, a)| a.bind(py).try_readonly().map(|r| (*k, r)))
            .collect::<Result<_, _>>()
            .map_err(internal)?;
        let images = MapImages::new(
            self.height,
            self.width,
            base_color.as_ref().map(|a| a.as_slice()).transpose().map_err(internal)?,
            radius_mm.as_ref().map(|a| a.as_slice()).transpose().map_err(internal)?,
            surface.iter().map(|(k, a)| a.as_slice().map(|s| (*k, s))).collect::<Result<_, _>>().map_err(internal)?,
        )?;
        write_images(py, &images, folder, prefix, exr, tiling)
    }
}

#[pymethods]
impl MapsPy {
    /// float32 (H, W, 3), Principled Base Color (read-only); None without the "albedo" output.
    #[getter]
    fn albedo<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f32>>> {
        self.albedo.as_ref().map(|a| a.bind(py).clone())
    }

    /// float32 (H, W, 3), Principled Subsurface Radius x Subsurface Scale, mm (read-only); None without the "radius"
    /// output.
    #[getter]
    fn radius<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f32>>> {
        self.radius.as_ref().map(|a| a.bind(py).clone())
    }

    /// float32 (H, W), Principled Specular IOR Level per texel (read-only); None without the "specular" output or
    /// when the oiliness is one value everywhere.
    #[getter]
    fn specular<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface_map(py, SURFACE_MAP_KINDS[0].name)
    }

    /// float32 (H, W), Principled Coat Weight per texel (read-only); None unless the oiliness varies under the
    /// "measured" surface.
    #[getter]
    fn coat_weight<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface_map(py, SURFACE_MAP_KINDS[1].name)
    }

    /// float32 (H, W), Principled Coat Roughness per texel (read-only); as ``coat_weight``.
    #[getter]
    fn coat_roughness<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f32>>> {
        self.surface_map(py, SURFACE_MAP_KINDS[2].name)
    }

    /// The specular inputs that are one value (a new dict; see :func:`maps`); None without the "specular" output.
    #[getter]
    fn specular_constants<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.specular_dict(py)
    }

    /// What was done (a new dict; see :func:`maps`).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.report_dict(py)
    }

    /// (H, W): the maps' height and width.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (self.height, self.width)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let found = match key.cast::<PyString>() {
            Ok(k) => self.item(py, k.to_str()?)?,
            Err(_) => None,
        };
        found.ok_or_else(|| PyKeyError::new_err(key.clone().unbind()))
    }

    fn __contains__(&self, key: &Bound<'_, PyAny>) -> PyResult<bool> {
        Ok(match key.cast::<PyString>() {
            Ok(k) => self.present().contains(&k.to_str()?),
            Err(_) => false,
        })
    }

    fn __len__(&self) -> usize {
        self.present().len()
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyIterator>> {
        PyList::new(py, self.present())?.try_iter()
    }

    /// The keys present, in the order "albedo", "radius", "specular", "coat_weight", "coat_roughness",
    /// "specular_constants", "report" (a ``KeysView``, as a dict's).
    fn keys<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        mapping_view(slf, "KeysView")
    }

    /// The values of ``keys()`` (a ``ValuesView``).
    fn values<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        mapping_view(slf, "ValuesView")
    }

    /// The (key, value) pairs of ``keys()`` (an ``ItemsView``).
    fn items<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        mapping_view(slf, "ItemsView")
    }

    /// ``result[key]`` if present, else ``default``.
    #[pyo3(signature = (key, default = None))]
    fn get<'py>(
        &self,
        py: Python<'py>,
        key: &Bound<'py, PyAny>,
        default: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let found = match key.cast::<PyString>() {
            Ok(k) => self.item(py, k.to_str()?)?,
            Err(_) => None,
        };
        Ok(found.or(default))
    }

    /// Write the maps this result holds as float EXRs with the core's writer (that of ``spectral-skin maps``),
    /// straight from its arrays, in ``folder`` (created if missing): ``albedo`` -> ``albedo.exr`` (channels R, G, B),
    /// ``radius`` -> ``radius.exr`` (R, G, B), ``specular`` -> ``specular.exr`` (Y), ``coat_weight`` ->
    /// ``coat_weight.exr`` (Y), ``coat_roughness`` -> ``coat_roughness.exr`` (Y); the file names and everything else
    /// as :func:`write_maps`.
    ///
    /// Arguments:
    ///     folder: the output folder.
    ///     prefix: None, or a file-name part prepended with "_" to each file name (no path separator).
    ///     precision: "half" (the default) or "float"; compression: "auto" (the default), "piz", "zip", "zips",
    ///         "rle" or "none" (as :func:`write_maps`).
    ///     tiles: None for one image; or a UDIM tile set stacked top to bottom: [(tile, rows), ...] in stacking
    ///         order, each tile 1001 to 2000 and given once, each at least one row, the rows adding up to H. Each
    ///         tile's rows become that tile's files (``albedo.1001.exr``, ...), which Blender loads as
    ///         ``albedo.<UDIM>.exr``.
    ///
    /// Every file (of every tile) is written as a temporary file in ``folder`` first and all are renamed into place
    /// together once all are written, so a failure leaves the existing files as they were. Then the files of an
    /// earlier write with the same prefix (and tiles) that this one did not write are removed.
    ///
    /// Returns:
    ///     {map name: path}, for the maps written; for a tile set the path holds ``<UDIM>``
    ///     (``<folder>/albedo.<UDIM>.exr``).
    ///
    /// Raises:
    ///     SpectralSkinError: a bad prefix, precision or compression; ``tiles`` that are not such pairs (the message
    ///         names ``tiles``, what is wrong and what is expected).
    ///     SpectralSkinIOError: a file that cannot be written (the message names it); nothing is changed.
    #[pyo3(signature = (folder, prefix = None, precision = "half", compression = "auto", tiles = None))]
    fn write<'py>(
        &self,
        py: Python<'py>,
        folder: PathBuf,
        prefix: Option<&str>,
        precision: &str,
        compression: &str,
        tiles: Option<Vec<(i64, i64)>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let exr = write_options(prefix, precision, compression)?;
        let tiling = Tiling::of(None, tiles, self.height)?;
        self.write_as(py, &folder, prefix, exr, tiling)
    }

    fn __repr__(&self) -> String {
        let strategy = serde_json::to_value(&self.report.strategy)
            .ok()
            .and_then(|v| v.get("name").and_then(|n| n.as_str().map(str::to_string)))
            .unwrap_or_default();
        let keys: Vec<&str> = self.present().into_iter().filter(|k| *k != "report").collect();
        format!("Maps({} x {}, {}; strategy {strategy})", self.width, self.height, keys.join(", "))
    }
}

/// A ``collections.abc`` view (`kind`: "KeysView", "ValuesView" or "ItemsView") of a result, as a dict's.
fn mapping_view<'py>(maps: &Bound<'py, MapsPy>, kind: &str) -> PyResult<Bound<'py, PyAny>> {
    maps.py().import("collections.abc")?.getattr(kind)?.call1((maps,))
}

/// Write the images of a :func:`maps` result as float EXRs, with the core's writer (that of ``spectral-skin maps``).
///
/// Each image present (and not None) becomes one file in ``folder`` (created if missing): "albedo" -> ``albedo.exr``
/// (channels R, G, B), "radius" -> ``radius.exr`` (R, G, B), "specular" -> ``specular.exr`` (Y), "coat_weight" and
/// "coat_roughness" -> ``coat_weight.exr`` and ``coat_roughness.exr`` (Y); with ``prefix``,
/// ``<prefix>_albedo.exr`` etc.; with ``tile`` (a UDIM tile number), ``albedo.1001.exr`` etc., one tile of a tile set Blender loads as ``albedo.<UDIM>.exr``; with ``tiles``, a tile
/// set stacked top to bottom, each tile's rows as that tile's files. Row 0 at the top; ``precision`` and
/// ``compression`` as the CLI's ``--precision`` and ``--compression``. The files (of every tile) are written as
/// temporary files in ``folder`` and renamed into place together once all are written, so a failure leaves the
/// existing files as they were. Then the files of an earlier write with the same prefix (and tiles) that this one
/// did not write (any of those files, and ``skin_maps.json``) are removed, so the folder
/// holds exactly this result's maps. No sidecar is written: the report is in the result.
///
/// A :class:`Maps` is written from its own arrays (as ``result.write(...)``). Read-only C-contiguous float32 arrays
/// (a :class:`Maps`' arrays, or slices of rows of them) are read in place; other arrays are copied (float64 rounded
/// to float32) first.
///
/// Arguments:
///     result: a :class:`Maps` (the result of :func:`maps`), or a mapping with any of "albedo" (H, W, 3), "radius"
///         (H, W, 3, mm), "specular", "coat_weight" and "coat_roughness" (H, W), float32 or float64 numpy arrays
///         (float64 is rounded to float32);
///         other keys are ignored.
///     folder: the output folder.
///     prefix: None, or a file-name part prepended with "_" to each file name (no path separator).
///     precision: "half" (16-bit, within 0.049 % of each value; the default) or "float" (32-bit).
///     compression: "auto" (the default: ZIPS for half, PIZ for float, or none for a file that would shrink by under
///         25 %), "piz", "zip", "zips", "rle" or "none".
///     tile: None, or the UDIM tile (1001 to 2000) the images are, written into each file name.
///     tiles: None, or the images as a UDIM tile set stacked top to bottom, as ``Maps.write``'s ``tiles``:
///         [(tile, rows), ...], each tile 1001 to 2000 given once, the rows adding up to H. Not with ``tile``.
///
/// Returns:
///     {map name ("albedo", "radius", "specular", "coat_weight", "coat_roughness"): path of the file written}, for
///     the images written; for ``tiles`` the path
///     holds ``<UDIM>``.
///
/// Raises:
///     SpectralSkinError: no image in ``result``, images whose (H, W) differ, an image of the wrong shape, a prefix
///         that is empty or holds a path separator, a tile out of range, ``tiles`` that are not such pairs (the
///         message names ``tiles``), both ``tile`` and ``tiles``.
///     SpectralSkinIOError: a file that cannot be written (the message names it).
///     TypeError: an image that is not a float32 or float64 numpy array.
#[pyfunction]
#[pyo3(
    name = "write_maps",
    signature = (result, folder, prefix = None, precision = "half", compression = "auto", tile = None, tiles = None)
)]
#[allow(clippy::too_many_arguments)]
pub(super) fn write_maps_py<'py>(
    py: Python<'py>,
    result: &Bound<'py, PyAny>,
    folder: PathBuf,
    prefix: Option<&str>,
    precision: &str,
    compression: &str,
    tile: Option<i64>,
    tiles: Option<Vec<(i64, i64)>>,
) -> PyResult<Bound<'py, PyDict>> {
    if let Some(t) = tile {
        check_tile("tile", t)?;
    }
    let exr = write_options(prefix, precision, compression)?;
    if let Ok(maps) = result.cast::<MapsPy>() {
        let maps = maps.get();
        return maps.write_as(py, &folder, prefix, exr, Tiling::of(tile, tiles, maps.height)?);
    }
    let mut images = Vec::with_capacity(MAP_KINDS.len());
    for kind in &MAP_KINDS {
        let key = kind.name;
        images.push(result_array(result, key, kind.channels.len())?.map(|(a, shape)| (key, shape, a)));
    }
    let sizes: Vec<(&str, usize, usize)> = images.iter().flatten().map(|(key, s, _)| (*key, s[0], s[1])).collect();
    let Some(&(_, height, width)) = sizes.first() else {
        let names: Vec<&str> = MAP_KINDS.iter().map(|k| k.name).collect();
        return Err(invalid("result", format!("holds none of {}: nothing to write", names.join(", "))));
    };
    if sizes.iter().any(|&(_, h, w)| (h, w) != (height, width)) {
        let listed: Vec<String> = sizes.iter().map(|(n, h, w)| format!("{n} ({h}, {w})")).collect();
        return Err(invalid("result", format!("the images must agree in (H, W); got {}", listed.join(", "))));
    }
    let tiling = Tiling::of(tile, tiles, height)?;
    let texels: Vec<Option<Texels>> =
        images.into_iter().map(|image| image.map(|(_, _, a)| Texels::of(a)).transpose()).collect::<PyResult<_>>()?;
    let slice = |i: usize| texels[i].as_ref().map(Texels::as_slice).transpose();
    let mut surface = Vec::new();
    for (i, kind) in MAP_KINDS.iter().enumerate().skip(2) {
        if let Some(s) = slice(i)? {
            surface.push((*kind, s));
        }
    }
    let images = MapImages::new(height, width, slice(0)?, slice(1)?, surface)?;
    write_images(py, &images, &folder, prefix, exr, tiling)
}
