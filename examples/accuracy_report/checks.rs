//! The references' own checks: the converged reference against a further refinement, and the transports (diffusion,
//! adding-doubling at several stream counts) against the project's Monte Carlo photon walk.

use serde::Serialize;
use spectral_skin::diffusion::{Combination, LayerStack, MultipoleTerms};
use spectral_skin::reflectance::LayeredOptions;
use spectral_skin::skin::skin_layers;
use spectral_skin::transport::{total_diffuse_reflectance, Transport};
use spectral_skin::{evaluate, Accuracy, SkinModel};

#[path = "../../tests/support/mc.rs"]
mod mc;
#[path = "../../tests/support/profile_figures.rs"]
mod profile_figures;

use crate::metrics::{max_relative, profile_log_error};
use crate::reference::{request, PresetReference, Task, PROFILE_GRID};

/// How much refining every knob of the reference once more changes it (worst over presets).
#[derive(Debug, Clone, Serialize)]
pub struct Convergence {
    pub finer: Accuracy,
    pub albedo_rel: f64,
    pub radius_rel: f64,
    pub profile_log: f64,
}

impl Convergence {
    /// Placeholder for partial runs (`--only`): NaN figures.
    pub fn not_measured() -> Convergence {
        Convergence { finer: Accuracy::reference(), albedo_rel: f64::NAN, radius_rel: f64::NAN, profile_log: f64::NAN }
    }
}

pub fn convergence(refs: &[PresetReference]) -> Convergence {
    let reference = Accuracy::reference();
    let finer = reference.refined();
    let mut c = Convergence { finer, albedo_rel: 0.0, radius_rel: 0.0, profile_log: 0.0 };
    for r in refs {
        let m = evaluate(&r.params, &request(finer, Task::Material)).expect("finer evaluation");
        let p = evaluate(&r.params, &request(finer, Task::Profile)).expect("finer profile");
        c.albedo_rel = c.albedo_rel.max(max_relative(m.diffuse_reflectance_rgb.unwrap(), r.albedo));
        c.radius_rel = c.radius_rel.max(max_relative(m.methods.unwrap().burley.subsurface_radius_mm, r.radius_mm));
        c.profile_log = c.profile_log.max(profile_log_error(
            &PROFILE_GRID.radii_mm(),
            p.profile.unwrap().rgb_per_mm2.as_ref().unwrap(),
            &r.profile,
        ));
    }
    c
}

/// Stream counts of the adding-doubling totals set beside the Monte Carlo.
pub const MC_STREAMS: [usize; 4] = [4, 8, 16, 32];

/// The total diffuse reflectance by diffusion and by adding-doubling against Monte Carlo for one preset and
/// wavelength.
#[derive(Debug, Clone, Serialize)]
pub struct McRow {
    pub preset: &'static str,
    pub wavelength_nm: f64,
    pub epidermis_albedo: f64,
    pub diffusion: f64,
    /// Adding-doubling totals at [`MC_STREAMS`] streams.
    pub adding_doubling: Vec<f64>,
    pub monte_carlo: f64,
    pub monte_carlo_se: f64,
    pub relative_difference: f64,
    pub photons: u64,
    pub seconds: f64,
}

pub const MC_WAVELENGTHS_NM: [f64; 3] = [450.0, 550.0, 650.0];

pub fn diffusion_vs_monte_carlo(refs: &[PresetReference], photons: u64) -> Vec<McRow> {
    let mut rows = Vec::new();
    for (k, r) in refs.iter().enumerate() {
        for (j, &wavelength_nm) in MC_WAVELENGTHS_NM.iter().enumerate() {
            let layers = skin_layers(&r.params, &SkinModel::default(), wavelength_nm);
            let diffusion = LayerStack::new(&layers).expect("layers").reflectance_hat(
                0.0,
                Combination::Directional,
                MultipoleTerms::All,
            );
            // Isotropic scattering with sigma_s = sigma_s' (the similarity relation the diffusion model assumes).
            let mc_layers: Vec<mc::McLayer> = layers
                .iter()
                .map(|l| mc::McLayer {
                    thickness_mm: l.thickness_mm,
                    sigma_a_per_mm: l.sigma_a_per_mm,
                    sigma_s_per_mm: l.sigma_s_reduced_per_mm,
                    ior: l.ior,
                })
                .collect();
            let start = std::time::Instant::now();
            let result = mc::simulate(&mc_layers, &mc::McConfig::new(photons, 1000 + 10 * k as u64 + j as u64, vec![]));
            let epi = layers[0];
            let adding_doubling =
                MC_STREAMS.iter().map(|&n| total_diffuse_reflectance(&layers, n).expect("adding-doubling")).collect();
            rows.push(McRow {
                preset: r.name,
                wavelength_nm,
                epidermis_albedo: epi.sigma_s_reduced_per_mm / (epi.sigma_a_per_mm + epi.sigma_s_reduced_per_mm),
                diffusion,
                adding_doubling,
                monte_carlo: result.reflectance,
                monte_carlo_se: result.reflectance_se,
                relative_difference: diffusion / result.reflectance - 1.0,
                photons,
                seconds: start.elapsed().as_secs_f64(),
            });
        }
    }
    rows
}

/// One stack's radial profile against the Monte Carlo: its figures, and each shape's relative errors [r50, r90, d].
#[derive(Debug, Clone, Serialize)]
pub struct ShapeRow {
    pub preset: &'static str,
    pub wavelength_nm: f64,
    pub mc_r50_mm: f64,
    pub mc_r90_mm: f64,
    pub mc_d_mm: f64,
    /// The default: the exact shapes' table.
    pub exact: [f64; 3],
    /// The multipole's shape scaled to the exact total (`adding_doubling_diffusion_shape`).
    pub diffusion_shape: [f64; 3],
    pub photons: u64,
}

/// The profile's shape (r50, r90 and the fitted Burley d) of each preset's stack at [`MC_WAVELENGTHS_NM`], exact and
/// diffusion-shaped, against the analog Monte Carlo (tests/support/profile_figures.rs, as tests/physics/exact_profile.rs
/// uses it).
pub fn shapes_vs_monte_carlo(refs: &[PresetReference], photons: u64) -> Vec<ShapeRow> {
    let mut rows = Vec::new();
    for (k, r) in refs.iter().enumerate() {
        for (j, &wavelength_nm) in MC_WAVELENGTHS_NM.iter().enumerate() {
            let layers = skin_layers(&r.params, &SkinModel::default(), wavelength_nm);
            let mc = profile_figures::monte_carlo(&layers, photons, 2000 + 10 * k as u64 + j as u64);
            let exact = profile_figures::model(&layers, &mc.edges_mm, &LayeredOptions::default());
            let before =
                LayeredOptions { transport: Transport::AddingDoublingDiffusionShape, ..LayeredOptions::default() };
            let diffusion_shape = profile_figures::model(&layers, &mc.edges_mm, &before);
            rows.push(ShapeRow {
                preset: r.name,
                wavelength_nm,
                mc_r50_mm: mc.figures.r50_mm,
                mc_r90_mm: mc.figures.r90_mm,
                mc_d_mm: mc.figures.d_mm,
                exact: exact.figures.relative_to(&mc.figures),
                diffusion_shape: diffusion_shape.figures.relative_to(&mc.figures),
                photons,
            });
        }
    }
    rows
}
