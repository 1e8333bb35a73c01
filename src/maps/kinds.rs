//! The kinds of texture map a run writes: each one's name on every front, file, channels, unit and Principled
//! input, defined once.

use crate::evaluate::MaterialOutput;

/// The colour space of a map's values as Blender loads the image: the scene's working space the Base Color was
/// computed in (linear RGB), or raw data.
pub const NON_COLOR: &str = "Non-Color";

/// One kind of texture map: its one name on every front (the `outputs` request, the key of the Python result and of
/// `write_maps`' images and written files, the add-on's texture, the file stem), its file, channels and unit, and
/// the Principled BSDF input it feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MapKind {
    pub name: &'static str,
    pub file: &'static str,
    pub channels: &'static [&'static str],
    /// The values' unit ("" for a dimensionless one).
    pub unit: &'static str,
    pub principled_input: &'static str,
    /// The colour space to load the image in: None for the run's working space (the colour of the Base Color),
    /// [`NON_COLOR`] for data.
    pub color_space: Option<&'static str>,
    /// The output (`outputs=`, `--outputs`) that computes it.
    pub output: MaterialOutput,
}

/// Principled Base Color for the method (the albedo itself without the radius output), linear RGB.
pub const ALBEDO_MAP: MapKind = MapKind {
    name: "albedo",
    file: "albedo.exr",
    channels: &["R", "G", "B"],
    unit: "",
    principled_input: "Base Color",
    color_space: None,
    output: MaterialOutput::Albedo,
};
/// Principled Subsurface Radius x Subsurface Scale for the method, mm.
pub const RADIUS_MAP: MapKind = MapKind {
    name: "radius",
    file: "radius.exr",
    channels: &["R", "G", "B"],
    unit: "mm",
    principled_input: "Subsurface Radius",
    color_space: Some(NON_COLOR),
    output: MaterialOutput::Radius,
};
/// Principled Specular IOR Level per texel (written only when the oiliness varies).
pub const SPECULAR_MAP: MapKind = MapKind {
    name: "specular",
    file: "specular.exr",
    channels: &["Y"],
    unit: "",
    principled_input: "Specular IOR Level",
    color_space: Some(NON_COLOR),
    output: MaterialOutput::Specular,
};
/// Principled Coat Weight per texel (the `measured` surface's sharp lobe; written only when the oiliness varies).
pub const COAT_WEIGHT_MAP: MapKind = MapKind {
    name: "coat_weight",
    file: "coat_weight.exr",
    channels: &["Y"],
    unit: "",
    principled_input: "Coat Weight",
    color_space: Some(NON_COLOR),
    output: MaterialOutput::Specular,
};
/// Principled Coat Roughness per texel (as [`COAT_WEIGHT_MAP`]).
pub const COAT_ROUGHNESS_MAP: MapKind = MapKind {
    name: "coat_roughness",
    file: "coat_roughness.exr",
    channels: &["Y"],
    unit: "",
    principled_input: "Coat Roughness",
    color_space: Some(NON_COLOR),
    output: MaterialOutput::Specular,
};
/// Every map kind, in the order results list them.
pub const MAP_KINDS: [MapKind; 5] = [ALBEDO_MAP, RADIUS_MAP, SPECULAR_MAP, COAT_WEIGHT_MAP, COAT_ROUGHNESS_MAP];
/// The single-channel surface maps: the specular output's, when the oiliness varies.
pub const SURFACE_MAP_KINDS: [MapKind; 3] = [SPECULAR_MAP, COAT_WEIGHT_MAP, COAT_ROUGHNESS_MAP];

/// Output file names.
pub const ALBEDO_FILE: &str = ALBEDO_MAP.file;
pub const RADIUS_FILE: &str = RADIUS_MAP.file;
pub const SPECULAR_FILE: &str = SPECULAR_MAP.file;
pub const SIDECAR_FILE: &str = "skin_maps.json";
