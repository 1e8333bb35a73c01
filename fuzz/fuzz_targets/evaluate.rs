//! `evaluate` with parameters, every model option, accuracy knobs, colour space, target and outputs decoded from the input,
//! inside and beyond the accepted ranges. The knobs that set the amount of work are kept small (at most 64 image
//! pairs, 32 profile radii, a wavelength step of 5 nm or more, the draft and default levels) so that one execution
//! stays in milliseconds; their ranges are the property tests' and `tests/physics/accuracy.rs`' business.
//! Asserts: Ok gives finite values everywhere (the specular inputs of either surface model too); spectral reflectance in [0, 1]; spectral profiles >= 0, and the RGB
//! profile too under `RgbMapping::NonNegative`; radii > 0; an error has a message; nothing panics.

#![no_main]

mod common;

use common::Bytes;
use libfuzzer_sys::fuzz_target;
use spectral_skin::color::{RgbMapping, WavelengthPlacement, ALL_RGB_MAPPINGS, ALL_WORKING_SPACES};
use spectral_skin::diffusion::{Combination, MultipoleTerms};
use spectral_skin::evaluate::ProfileGrid;
use spectral_skin::fit::blender_target::{BlenderVersion, Engine, Target};
use spectral_skin::skin::chromophores::{BloodSpectrum, EumelaninShape};
use spectral_skin::skin::scattering::ScatteringShape;
use spectral_skin::surface::lobes::ALL_SURFACE_MODELS;
use spectral_skin::{evaluate, AccuracyLevel, Outputs, Request, SkinModel, SkinParams};

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes::new(data);
    let params = SkinParams {
        melanin: b.linear(-0.05, 0.55),
        melanin_blend: b.linear(-0.1, 1.1),
        hemoglobin: b.linear(-0.01, 0.11),
        oiliness: b.linear(-0.1, 1.1),
        epidermis_thickness_mm: b.log_value(-5.0, 2.0),
        baseline_absorption_scale: b.linear(-1.0, 12.0),
        blood_oxygenation: b.linear(-0.1, 1.1),
    };
    let flags = b.byte();
    let outputs = Outputs {
        albedo: flags & 1 != 0,
        radius: flags & 2 != 0,
        profile_rgb: flags & 4 != 0,
        profile_spectral: flags & 8 != 0,
        spectrum: flags & 16 != 0,
        specular: flags & 32 != 0,
    };
    let mut request = Request::new(outputs);
    let level = if b.byte() % 2 == 0 { AccuracyLevel::Draft } else { AccuracyLevel::Default };
    request.accuracy = level.accuracy();
    let knobs = b.byte();
    if knobs & 1 != 0 {
        let step = b.linear(5.0, 120.0);
        request.accuracy.wavelength_step_nm = if step.is_finite() && step < 5.0 && step > 0.0 { 5.0 } else { step };
    }
    if knobs & 2 != 0 {
        request.accuracy.wavelength_placement =
            [WavelengthPlacement::Uniform, WavelengthPlacement::CmfAdapted, WavelengthPlacement::RgbShortcut]
                [usize::from(b.byte() % 3)];
    }
    if knobs & 4 != 0 {
        request.accuracy.multipole_terms = MultipoleTerms::Pairs(u32::from(b.byte() % 65));
    }
    if knobs & 8 != 0 {
        request.accuracy.profile_grid = ProfileGrid {
            r_min_mm: b.log_value(-7.0, 5.0),
            r_max_mm: b.log_value(-7.0, 5.0),
            count: usize::from(b.byte() % 33),
        };
    }
    if knobs & 16 != 0 {
        request.model = SkinModel {
            eumelanin_k_per_mm: b.log_value(0.0, 14.0),
            dermis_thickness_mm: if b.byte() % 2 == 0 { f64::INFINITY } else { b.log_value(-4.0, 5.0) },
            blood_vessel_radius_mm: if b.byte() % 2 == 0 { 0.0 } else { b.log_value(-5.0, 1.0) },
            // Every option a user can set (`--model`, Python's `model=`), inside and beyond its range.
            eumelanin_shape: match b.byte() % 3 {
                0 => EumelaninShape::Dj2006,
                1 => EumelaninShape::PowerLaw { exponent: b.linear(-10.0, 2.0) },
                _ => EumelaninShape::Exponential { k_per_nm: b.linear(-0.01, 0.1) },
            },
            scattering_shape: match b.byte() % 2 {
                0 => ScatteringShape::Dj2006,
                _ => ScatteringShape::MieRayleigh { f_ray: b.linear(-0.5, 1.5), b_mie: b.linear(-1.0, 5.0) },
            },
            epidermal_carotene_umol_per_l: if b.byte() % 2 == 0 { 0.0 } else { b.log_value(-3.0, 3.0) },
            blood_spectrum: if b.byte() % 2 == 0 { BloodSpectrum::Dj2006 } else { BloodSpectrum::WholeBlood2014 },
            epidermal_hemoglobin: if b.byte() % 2 == 0 { 0.0 } else { b.linear(-0.02, 0.15) },
        };
    }
    if knobs & 32 != 0 {
        request.combination = if b.byte() % 2 == 0 { Combination::Directional } else { Combination::Symmetric };
    }
    request.working_space = ALL_WORKING_SPACES[usize::from(b.byte() % 3)];
    request.target = Target {
        blender: BlenderVersion { major: u16::from(b.byte() % 8), minor: u16::from(b.byte() % 12) },
        engine: if b.byte() % 2 == 0 { Engine::Cycles } else { Engine::Eevee },
    };
    request.rgb_mapping = ALL_RGB_MAPPINGS[usize::from(b.byte() % 2)];
    request.surface = ALL_SURFACE_MODELS[usize::from(b.byte() % 2)];

    let ev = match evaluate(&params, &request) {
        Ok(ev) => ev,
        Err(e) => {
            assert!(!e.to_string().is_empty());
            return;
        }
    };
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    if let Some(albedo) = ev.diffuse_reflectance_rgb {
        assert!(finite(&albedo), "albedo {albedo:?} for {params:?} {request:?}");
    }
    if let Some(methods) = &ev.methods {
        for (method, m) in methods.iter() {
            assert!(finite(&m.base_color) && finite(&m.expected_albedo), "{method:?} {m:?}");
            assert!(m.subsurface_radius_mm.iter().all(|r| r.is_finite() && *r > 0.0), "{method:?} {m:?}");
        }
    }
    if let Some(spectrum) = &ev.spectral_reflectance {
        assert!(spectrum.iter().all(|r| r.is_finite() && (0.0..=1.0).contains(r)), "spectrum {spectrum:?}");
    }
    if let Some(profile) = &ev.profile {
        if let Some(rgb) = &profile.rgb_per_mm2 {
            assert_eq!(rgb.len(), profile.radii_mm.len());
            assert!(rgb.iter().all(|v| finite(v)), "rgb profile {rgb:?}");
            if request.rgb_mapping == RgbMapping::NonNegative {
                assert!(rgb.iter().flatten().all(|&v| v >= 0.0), "non-negative rgb profile {rgb:?}");
            }
        }
        if let Some(spectral) = &profile.spectral_per_mm2 {
            for p in spectral {
                assert_eq!(p.len(), profile.radii_mm.len());
                assert!(p.iter().all(|x| x.is_finite() && *x >= 0.0), "spectral profile {p:?}");
            }
        }
    }
    if let Some(s) = &ev.specular {
        let v = serde_json::to_value(s).expect("specular serialises");
        let fields = v.as_object().expect("specular is an object");
        // Every field a finite number, but the surface model's name.
        let finite = |(k, x): (&String, &serde_json::Value)| k == "surface" || x.as_f64().is_some_and(f64::is_finite);
        assert!(fields.iter().all(finite), "{v}");
        assert!(matches!(fields["surface"].as_str(), Some("paper" | "measured")), "{v}");
        assert!((0.0..=1.0).contains(&s.coat_weight) && s.specular_ior_level >= 0.0, "{v}");
    }
});
