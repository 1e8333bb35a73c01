//! The Blender target of a mapping: (Blender version, render engine), and per subsurface method how the model's
//! albedo and Burley radius become Principled BSDF inputs there.
//!
//! What differs between targets is kept as data in [`VERSION_TABLE`]: one entry per Blender version that changed
//! behaviour or was tested, each naming the EEVEE engine id and, per subsurface method, the model of what Cycles
//! does with Base Color and Radius. A version resolves to the newest entry at or below it; it is `tested` only if an
//! entry for exactly that version is marked tested. So a new Blender version is one entry (and one test).
//! docs/blender-targets.md describes each mapping and its sources.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::burley::christensen_burley_s;
use super::random_walk::{base_color_for, width_factor, RandomWalkModel};
use super::random_walk_skin::{skin_base_color, skin_radius_factor, skin_width_factor, SKIN_SUBSURFACE_IOR};
use super::{MethodParams, SubsurfaceMethod};
use crate::error::SkinError;

/// A Blender release line, `MAJOR.MINOR` (the patch level does not change subsurface behaviour).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct BlenderVersion {
    pub major: u16,
    pub minor: u16,
}

/// The oldest Blender the mappings support.
pub const OLDEST_SUPPORTED: BlenderVersion = BlenderVersion { major: 4, minor: 2 };
/// The default target version: the current release.
pub const CURRENT_RELEASE: BlenderVersion = BlenderVersion { major: 5, minor: 3 };

impl BlenderVersion {
    /// A supported version from its parts (`bpy.app.version` gives (major, minor, patch); the patch is ignored).
    /// Errors name the input and the supported range.
    pub fn from_parts(parts: &[i64]) -> Result<BlenderVersion, SkinError> {
        let shown = parts.iter().map(|p| p.to_string()).collect::<Vec<_>>().join(".");
        let bad = || {
            SkinError::invalid(
                "blender version",
                format!(
                    "expected MAJOR.MINOR or MAJOR.MINOR.PATCH (e.g. \"5.3\"; a patch release means its minor \
                     release) or (major, minor[, patch]); got {shown:?}. {}",
                    supported_range()
                ),
            )
        };
        if !(2..=3).contains(&parts.len()) || parts.iter().any(|&p| !(0..=i64::from(u16::MAX)).contains(&p)) {
            return Err(bad());
        }
        let version = BlenderVersion { major: parts[0] as u16, minor: parts[1] as u16 };
        if version < OLDEST_SUPPORTED {
            return Err(SkinError::invalid(
                "blender version",
                format!("Blender {version} is not supported. {}", supported_range()),
            ));
        }
        Ok(version)
    }

    /// The table entry in force for this version: the newest at or below it.
    pub fn entry(self) -> &'static VersionEntry {
        VERSION_TABLE.iter().rev().find(|e| e.version <= self).unwrap_or(&VERSION_TABLE[0])
    }

    /// Whether renders validated the mappings for `engine` in exactly this version.
    pub fn tested(self, engine: Engine) -> bool {
        let e = self.entry();
        e.version == self && if engine == Engine::Eevee { e.eevee_tested } else { e.tested }
    }
}

/// "supported: 4.2 and newer; tested: 4.2, 4.5, ..." from the table.
fn supported_range() -> String {
    let tested: Vec<String> = VERSION_TABLE.iter().filter(|e| e.tested).map(|e| e.version.to_string()).collect();
    format!("Supported: Blender {OLDEST_SUPPORTED} and newer (tested: {})", tested.join(", "))
}

impl fmt::Display for BlenderVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.major, self.minor)
    }
}

impl FromStr for BlenderVersion {
    type Err = SkinError;
    /// `"5.2"` or `"5.2.3"`: a patch release means its minor release (5.2.3 is 5.2), said so in every front's help.
    fn from_str(text: &str) -> Result<BlenderVersion, SkinError> {
        let parts: Option<Vec<i64>> = text.trim().split('.').map(|p| p.parse::<u16>().ok().map(i64::from)).collect();
        match parts {
            Some(p) => BlenderVersion::from_parts(&p),
            None => Err(SkinError::invalid(
                "blender version",
                format!(
                    "expected MAJOR.MINOR or MAJOR.MINOR.PATCH (e.g. \"5.3\"; a patch release means its minor \
                     release); got {text:?}. {}",
                    supported_range()
                ),
            )),
        }
    }
}

impl Serialize for BlenderVersion {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for BlenderVersion {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<BlenderVersion, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// Blender's render engines that render subsurface scattering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum), value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Engine {
    #[default]
    Cycles,
    /// EEVEE (EEVEE Next in 4.2-4.5): every subsurface method renders as a screen-space Burley profile.
    Eevee,
}

impl Engine {
    pub const ALL: [Engine; 2] = [Engine::Cycles, Engine::Eevee];

    pub fn name(self) -> &'static str {
        match self {
            Engine::Cycles => "cycles",
            Engine::Eevee => "eevee",
        }
    }

    /// The engine named `name` (snake_case, as in JSON and Python).
    pub fn from_name(name: &str) -> Result<Engine, SkinError> {
        Engine::ALL.into_iter().find(|e| e.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Engine::ALL.iter().map(|e| e.name()).collect();
            SkinError::invalid("engine", format!("expected one of {}; got {name:?}", names.join(", ")))
        })
    }

    /// `scene.render.engine` in `version`.
    pub fn blender_id(self, version: BlenderVersion) -> &'static str {
        match self {
            Engine::Cycles => CYCLES_ID,
            Engine::Eevee => version.entry().eevee_id,
        }
    }
}

/// Cycles' engine id, the same in every supported version.
pub const CYCLES_ID: &str = "CYCLES";

/// What a method's Radius means to Cycles, given the walk's transport mean free path `l` (for Burley: d).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RadiusConvention {
    /// Radius x Scale = 4 pi l (`bssrdf_setup_radius` scales by 1/(4 pi)): Burley, random walk up to 5.1, Legacy.
    FourPiMeanFreePath,
    /// Radius x Scale = l: `RANDOM_WALK` from 5.2 on (measured in bpy 5.2.3 and 5.3.0; the source change is
    /// "Removing legacy scaling of the subsurface radius to match MaterialX", `blender/blender` e5f416414).
    MeanFreePath,
    /// Radius x Scale x sqrt(3 (1 - alpha')) = l, alpha' from the dipole inversion (`fit::random_walk_skin`).
    SkinDipole,
}

/// How Cycles renders one method in one version: the model the mapping inverts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum MethodModel {
    /// Christensen-Burley: Base Color rendered exactly, d = Radius x Scale / (4 pi).
    Burley,
    /// A random walk: the alpha mapping and what Radius means.
    RandomWalk { alpha: RandomWalkModel, radius: RadiusConvention },
}

/// One method in one table entry.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MethodEntry {
    pub method: SubsurfaceMethod,
    pub model: MethodModel,
    /// Whether renders validated this method's mapping (in the entry's tested versions).
    pub tested: bool,
}

/// One row of the version table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VersionEntry {
    /// First version this row applies to (until the next row).
    pub version: BlenderVersion,
    /// `scene.render.engine` of EEVEE in this version.
    pub eevee_id: &'static str,
    /// The subsurface methods the Principled BSDF offers, in Blender's menu order.
    pub methods: &'static [MethodEntry],
    /// Whether the Cycles render tests ran in exactly this version.
    pub tested: bool,
    /// Whether the EEVEE edge render test (`tests/blender/test_eevee_edge.py`) validated the EEVEE mapping in exactly
    /// this version. Not in 4.2: its EEVEE subsurface pass does not repeat from run to run under Mesa llvmpipe
    /// (docs/blender-render-tests.md, EEVEE edge).
    pub eevee_tested: bool,
}

const BURLEY: MethodEntry = MethodEntry { method: SubsurfaceMethod::Burley, model: MethodModel::Burley, tested: true };
/// The random walk up to 5.1 (Wrenninge fit, Radius = 4 pi l): `RANDOM_WALK` there, `RANDOM_WALK_LEGACY` after.
const FIT_WALK: MethodModel =
    MethodModel::RandomWalk { alpha: RandomWalkModel::WrenningeFit, radius: RadiusConvention::FourPiMeanFreePath };
/// `RANDOM_WALK_SKIN`: the Wrenninge fit, radius through the dipole; its flat response and its width are measured
/// tables (`docs/data/random_walk_skin_flat.json`, `docs/data/random_walk_width.json`), validated by the flat-slab and
/// edge render tests of every version.
const SKIN: MethodEntry = MethodEntry {
    method: SubsurfaceMethod::RandomWalkSkin,
    model: MethodModel::RandomWalk { alpha: RandomWalkModel::WrenningeFit, radius: RadiusConvention::SkinDipole },
    tested: true,
};
/// Methods of Blender 4.2-5.1.
const METHODS_4_2: &[MethodEntry] =
    &[BURLEY, MethodEntry { method: SubsurfaceMethod::RandomWalk, model: FIT_WALK, tested: true }, SKIN];
/// Methods of Blender 5.2 on: `RANDOM_WALK` inverts by Van de Hulst and reads Radius as the mean free path
/// (`blender/cycles` 695bae346ba1, PR #156355); the old walk stays as `RANDOM_WALK_LEGACY`.
const METHODS_5_2: &[MethodEntry] = &[
    BURLEY,
    MethodEntry {
        method: SubsurfaceMethod::RandomWalk,
        model: MethodModel::RandomWalk { alpha: RandomWalkModel::VanDeHulst, radius: RadiusConvention::MeanFreePath },
        tested: true,
    },
    MethodEntry { method: SubsurfaceMethod::RandomWalkLegacy, model: FIT_WALK, tested: true },
    SKIN,
];

/// EEVEE's engine id: `BLENDER_EEVEE_NEXT` in 4.2-4.5, `BLENDER_EEVEE` from 5.0.
const EEVEE_NEXT: &str = "BLENDER_EEVEE_NEXT";
const EEVEE: &str = "BLENDER_EEVEE";

const fn v(major: u16, minor: u16) -> BlenderVersion {
    BlenderVersion { major, minor }
}

/// The table, oldest first. A new Blender version: one row here, and one test in `tests/maps/blender_targets.rs`.
pub const VERSION_TABLE: &[VersionEntry] = &[
    VersionEntry { version: v(4, 2), eevee_id: EEVEE_NEXT, methods: METHODS_4_2, tested: true, eevee_tested: false },
    VersionEntry { version: v(4, 5), eevee_id: EEVEE_NEXT, methods: METHODS_4_2, tested: true, eevee_tested: true },
    VersionEntry { version: v(5, 0), eevee_id: EEVEE, methods: METHODS_4_2, tested: true, eevee_tested: true },
    VersionEntry { version: v(5, 2), eevee_id: EEVEE, methods: METHODS_5_2, tested: true, eevee_tested: true },
    VersionEntry { version: v(5, 3), eevee_id: EEVEE, methods: METHODS_5_2, tested: true, eevee_tested: true },
];

/// A mapping target: Blender version and render engine. Defaults to the current release with Cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Target {
    pub blender: BlenderVersion,
    pub engine: Engine,
}

impl Default for Target {
    fn default() -> Self {
        Target { blender: CURRENT_RELEASE, engine: Engine::Cycles }
    }
}

/// A target as results report it: version, engine and whether renders validated that engine in that version;
/// serialized with `untested_reason` ([`Target::untested_reason`]) when they have not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetInfo {
    pub blender: BlenderVersion,
    pub engine: Engine,
    pub tested: bool,
}

impl TargetInfo {
    pub fn untested_reason(&self) -> Option<String> {
        Target { blender: self.blender, engine: self.engine }.untested_reason()
    }
}

impl Serialize for TargetInfo {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let reason = self.untested_reason();
        let mut st = s.serialize_struct("TargetInfo", 3 + usize::from(reason.is_some()))?;
        st.serialize_field("blender", &self.blender)?;
        st.serialize_field("engine", &self.engine)?;
        st.serialize_field("tested", &self.tested)?;
        if let Some(reason) = reason {
            st.serialize_field("untested_reason", &reason)?;
        }
        st.end()
    }
}

impl Target {
    /// The target for a version string (`"5.2"`, `"5.2.3"`) and an engine name (`"cycles"`, `"eevee"`).
    pub fn parse(blender: &str, engine: &str) -> Result<Target, SkinError> {
        Ok(Target { blender: blender.parse()?, engine: Engine::from_name(engine)? })
    }

    pub fn info(&self) -> TargetInfo {
        TargetInfo { blender: self.blender, engine: self.engine, tested: self.blender.tested(self.engine) }
    }

    /// Why renders have not validated this target and what it uses instead (`None` when they have): the one wording
    /// every front shows.
    pub fn untested_reason(&self) -> Option<String> {
        let (version, engine) = (self.blender, self.engine);
        if version.tested(engine) {
            return None;
        }
        let entry = version.entry();
        let newest = VERSION_TABLE[VERSION_TABLE.len() - 1].version;
        let engine_name = match engine {
            Engine::Cycles => "Cycles",
            Engine::Eevee => "EEVEE",
        };
        Some(if version > newest {
            format!(
                "Blender {version} is newer than the versions Spectral Skin was tested with (up to {newest}): it uses \
                 the newest known behaviour"
            )
        } else if entry.version != version {
            format!("Blender {version} was not tested: it uses the behaviour of Blender {}", entry.version)
        } else {
            format!(
                "{engine_name} in Blender {version} was not validated by renders: it uses the same mapping as \
                 {engine_name} in the versions that were"
            )
        })
    }

    /// The methods this version's Principled BSDF offers (EEVEE offers the same menu and renders each as Burley).
    pub fn methods(&self) -> impl Iterator<Item = SubsurfaceMethod> {
        self.blender.entry().methods.iter().map(|m| m.method)
    }

    /// `method`'s table entry here, or an error naming the methods this version offers.
    pub fn method_entry(&self, method: SubsurfaceMethod) -> Result<&'static MethodEntry, SkinError> {
        let entry = self.blender.entry();
        entry.methods.iter().find(|m| m.method == method).ok_or_else(|| {
            let offered: Vec<&str> = entry.methods.iter().map(|m| m.method.name()).collect();
            SkinError::invalid(
                "subsurface method",
                format!(
                    "{} is not offered by Blender {} (methods there: {})",
                    method.name(),
                    self.blender,
                    offered.join(", ")
                ),
            )
        })
    }

    /// Principled Base Color and Radius x Scale for `method` here, per channel, from the model's total diffuse
    /// reflectance `albedo` and the Christensen-Burley fit `burley_radius_mm` (4 pi d, the Cycles Burley radius).
    pub fn map(
        &self,
        method: SubsurfaceMethod,
        albedo: [f64; 3],
        burley_radius_mm: [f64; 3],
    ) -> Result<MethodParams, SkinError> {
        let entry = self.method_entry(method)?;
        if self.engine == Engine::Eevee {
            return Ok(eevee_burley(albedo, burley_radius_mm));
        }
        Ok(match entry.model {
            MethodModel::Burley => {
                MethodParams { base_color: albedo, subsurface_radius_mm: burley_radius_mm, expected_albedo: albedo }
            }
            MethodModel::RandomWalk { alpha, radius } => {
                let colors = [0, 1, 2].map(|c| match radius {
                    RadiusConvention::SkinDipole => skin_base_color(albedo[c]),
                    _ => base_color_for(alpha, albedo[c]),
                });
                let base_color = colors.map(|c| c.base_color);
                let subsurface_radius_mm = [0, 1, 2].map(|c| {
                    // The walk's transport mean free path for Burley length d = radius / (4 pi), from the measured
                    // width of the walk that renders it.
                    let d_mm = burley_radius_mm[c] / (4.0 * PI);
                    match radius {
                        RadiusConvention::FourPiMeanFreePath => 4.0 * PI * d_mm * width_factor(alpha, base_color[c]),
                        RadiusConvention::MeanFreePath => d_mm * width_factor(alpha, base_color[c]),
                        RadiusConvention::SkinDipole => {
                            d_mm * skin_width_factor(base_color[c])
                                / skin_radius_factor(base_color[c], SKIN_SUBSURFACE_IOR)
                        }
                    }
                });
                MethodParams { base_color, subsurface_radius_mm, expected_albedo: colors.map(|c| c.achieved_albedo) }
            }
        })
    }
}

/// EEVEE's Burley: `d = Radius x Scale / (4 pi) / s(A_n)` with `A_n = A / max(A)` per channel (docs/blender-targets.md, EEVEE;
/// `burley_setup` in EEVEE's subsurface shaders), so Radius x Scale = 4 pi d s(A_n) gives the Cycles profile. An
/// all-black albedo (max 0, or not finite) takes A_n = 0. Base Color renders as the albedo.
pub fn eevee_burley(albedo: [f64; 3], burley_radius_mm: [f64; 3]) -> MethodParams {
    let max = albedo.iter().cloned().fold(0.0, f64::max);
    let normalized = albedo.map(|a| if max > 0.0 && max.is_finite() { a / max } else { 0.0 });
    MethodParams {
        base_color: albedo,
        subsurface_radius_mm: [0, 1, 2].map(|c| burley_radius_mm[c] * christensen_burley_s(normalized[c])),
        expected_albedo: albedo,
    }
}

/// The table as the fronts read it (Python's `blender_targets()`, the add-on's enums and engine detection).
#[derive(Debug, Clone, Serialize)]
pub struct TargetsDescription {
    pub oldest_supported: BlenderVersion,
    pub current_release: BlenderVersion,
    pub default: TargetInfo,
    pub tested_versions: Vec<BlenderVersion>,
    pub engines: Vec<EngineDescription>,
    pub methods: Vec<MethodDescription>,
    pub versions: Vec<VersionDescription>,
}

#[derive(Debug, Clone, Serialize)]
pub struct EngineDescription {
    pub name: &'static str,
}

#[derive(Debug, Clone, Serialize)]
pub struct MethodDescription {
    pub name: &'static str,
    /// Principled BSDF `subsurface_method` identifier.
    pub blender_id: &'static str,
}

#[derive(Debug, Clone, Serialize)]
pub struct VersionDescription {
    pub version: BlenderVersion,
    /// Cycles render tests ran in this version.
    pub tested: bool,
    /// The EEVEE edge render test ran in this version.
    pub eevee_tested: bool,
    /// Engine name -> `scene.render.engine` id in this version.
    pub engine_ids: std::collections::BTreeMap<&'static str, &'static str>,
    pub methods: Vec<VersionMethodDescription>,
}

#[derive(Debug, Clone, Serialize)]
pub struct VersionMethodDescription {
    pub name: &'static str,
    pub blender_id: &'static str,
    pub tested: bool,
    pub model: MethodModel,
}

/// Describe the table.
pub fn describe_targets() -> TargetsDescription {
    TargetsDescription {
        oldest_supported: OLDEST_SUPPORTED,
        current_release: CURRENT_RELEASE,
        default: Target::default().info(),
        tested_versions: VERSION_TABLE.iter().filter(|e| e.tested).map(|e| e.version).collect(),
        engines: Engine::ALL.iter().map(|e| EngineDescription { name: e.name() }).collect(),
        methods: SubsurfaceMethod::ALL
            .iter()
            .map(|m| MethodDescription { name: m.name(), blender_id: m.blender_id() })
            .collect(),
        versions: VERSION_TABLE
            .iter()
            .map(|e| VersionDescription {
                version: e.version,
                tested: e.tested,
                eevee_tested: e.eevee_tested,
                engine_ids: Engine::ALL.iter().map(|g| (g.name(), g.blender_id(e.version))).collect(),
                methods: e
                    .methods
                    .iter()
                    .map(|m| VersionMethodDescription {
                        name: m.method.name(),
                        blender_id: m.method.blender_id(),
                        tested: m.tested,
                        model: m.model,
                    })
                    .collect(),
            })
            .collect(),
    }
}
