//! A change detector, not a reference: the model's numbers (every preset evaluated with both transports, a spectrum
//! fit and an albedo fit, each rounded to five significant digits) hashed and recorded beside the model version they
//! belong to. When they change this fails until `MODEL_VERSION` (src/stamp.rs) is raised and the new fingerprint
//! recorded here, and then the doc test (doc_stamps.rs) fails until every stamped doc and figure is regenerated
//! (docs/tests.md, Stamped docs). Correctness is the other tests' business: this only makes a change visible.

use serde_json::Value;
use spectral_skin::inverse::albedo::{fit_albedo, AlbedoFitOptions};
use spectral_skin::inverse::{fit_spectrum, FitOptions};
use spectral_skin::transport::Transport;
use spectral_skin::{evaluate, Outputs, Request, MODEL_VERSION, PRESETS};

/// The fingerprint of each model version (the newest last).
const FINGERPRINTS: &[(u32, u64)] = &[(1, 0x9d82_5dd6_8113_a80f)];

/// `value` with every number rounded to five significant digits (the last bits of a sum are not the model's numbers).
fn rounded(value: Value) -> Value {
    match value {
        Value::Number(n) => {
            let x = n.as_f64().unwrap_or(0.0);
            let text = format!("{x:.4e}");
            Value::String(if text.starts_with("-0.0000e") { "0.0000e0".into() } else { text })
        }
        Value::Array(items) => Value::Array(items.into_iter().map(rounded).collect()),
        Value::Object(map) => Value::Object(map.into_iter().map(|(k, v)| (k, rounded(v))).collect()),
        other => other,
    }
}

/// FNV-1a, 64 bits: a hash whose value is the same on every platform and release (std's is not promised to be).
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

fn model_numbers() -> Value {
    let outputs = Outputs { albedo: true, radius: true, specular: true, spectrum: true, ..Outputs::default() };
    let mut numbers = Vec::new();
    for transport in [Transport::AddingDoubling, Transport::Diffusion] {
        let request = Request { transport, ..Request::new(outputs) };
        for preset in PRESETS {
            let mut ev = serde_json::to_value(evaluate(&preset.params, &request).unwrap()).unwrap();
            for volatile in ["work", "seconds"] {
                ev.as_object_mut().unwrap().remove(volatile);
            }
            numbers.push(ev);
        }
    }
    let ev = evaluate(&PRESETS[0].params, &Request::new(outputs)).unwrap();
    let (wavelengths_nm, reflectance) = (ev.wavelengths_nm.unwrap(), ev.spectral_reflectance.unwrap());
    let fit = fit_spectrum(&wavelengths_nm, &reflectance, &FitOptions::default()).unwrap();
    numbers.push(serde_json::to_value(fit.params).unwrap());
    let albedo = fit_albedo([0.5, 0.35, 0.28], &AlbedoFitOptions::default()).unwrap();
    numbers.push(serde_json::to_value((albedo.params, albedo.albedo_rgb)).unwrap());
    rounded(Value::Array(numbers))
}

#[test]
fn the_model_version_changes_with_the_models_numbers() {
    let fingerprint = fnv1a(&model_numbers().to_string());
    let (recorded_version, recorded) = *FINGERPRINTS.last().unwrap();
    assert_eq!(recorded_version, MODEL_VERSION, "record the fingerprint of MODEL_VERSION {MODEL_VERSION} here");
    assert_eq!(
        fingerprint, recorded,
        "the model's numbers changed (fingerprint {fingerprint:#x}, recorded {recorded:#x} for model {MODEL_VERSION}): \
         raise MODEL_VERSION in src/stamp.rs, append ({}, {fingerprint:#x}) to FINGERPRINTS here, and regenerate the \
         stamped docs (docs/tests.md, Stamped docs)",
        MODEL_VERSION + 1
    );
}
