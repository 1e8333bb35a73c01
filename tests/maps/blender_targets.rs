//! The Blender target table and the per-target mappings, against independent references: van de Hulst's albedo
//! formula and the half-space H-function, EEVEE's s(A_n) worked by hand, the figures the issue measured in Blender
//! renders, and the version rules of the table.

use std::f64::consts::PI;

use spectral_skin::fit::blender_target::{eevee_burley, BlenderVersion, Engine, Target, VERSION_TABLE};
use spectral_skin::fit::random_walk::{
    base_color_for, flat_albedo, van_de_hulst_single_scatter_albedo, width_factor, RandomWalkModel,
};
use spectral_skin::fit::random_walk_skin::skin_width_factor;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::transport::half_space::half_space_hemispherical_albedo;
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

fn target(blender: &str, engine: &str) -> Target {
    Target::parse(blender, engine).unwrap()
}

fn material(preset: &str, blender: &str, engine: &str) -> spectral_skin::Evaluation {
    let request = Request { target: target(blender, engine), ..Request::new(Outputs::material()) };
    evaluate(&SkinParams::preset(preset).unwrap(), &request).unwrap()
}

/// Van de Hulst's semi-infinite-medium albedo for diffuse light, `R(a) = (1 - s)(1 - 0.139 s) / (1 + 1.17 s)` with
/// `s = sqrt(1 - a)` (van de Hulst 1980, as quoted by d'Eon, "A Hitchhiker's Guide to Multiple Scattering",
/// section 53): the relation whose inverse eq. 53.7 is.
fn van_de_hulst_albedo(alpha: f64) -> f64 {
    let s = (1.0 - alpha).sqrt();
    (1.0 - s) * (1.0 - 0.139 * s) / (1.0 + 1.17 * s)
}

/// Eq. 53.7 inverts van de Hulst's relation: R(alpha(A)) = A. Measured worst |R - A| over A = 0.01..0.99: 4e-5
/// (the published constants are rounded to 6 digits).
#[test]
fn van_de_hulst_alpha_inverts_van_de_hulst_relation() {
    let mut worst: f64 = 0.0;
    for i in 1..=99 {
        let a = 0.01 * i as f64;
        let alpha = van_de_hulst_single_scatter_albedo(a, 0.0);
        worst = worst.max((van_de_hulst_albedo(alpha) - a).abs());
    }
    println!("max |R_vdH(alpha(A)) - A| = {worst:.2e}");
    assert!(worst < 1e-4, "{worst}");
    // The rounded constants leave alpha(0) = 5.7e-6, not 0; at A = 1 the clamp holds.
    let alpha_0 = van_de_hulst_single_scatter_albedo(0.0, 0.0);
    assert!(alpha_0 < 1e-5, "alpha(0) = {alpha_0:e}");
    assert_eq!(van_de_hulst_single_scatter_albedo(1.0, 0.0), 0.999999);
}

/// The formula's intent: alpha(A) is the single-scattering albedo whose isotropic half-space has hemispherical
/// (diffuse-light) albedo A. By the H-function (converged to 1e-12), measured: |R_hemi(alpha(A)) - A| <= 2.06e-3
/// over A = 0.01..0.99 (van de Hulst's approximation error; 2.4 % relative at A = 0.05), relative <= 1.02 % for
/// A >= 0.2. Bounds: 2.5e-3 and 1.1 %.
#[test]
fn van_de_hulst_alpha_gives_half_space_albedo() {
    let (mut worst, mut worst_rel): (f64, f64) = (0.0, 0.0);
    for i in 1..=99 {
        let a = 0.01 * i as f64;
        let r = half_space_hemispherical_albedo(van_de_hulst_single_scatter_albedo(a, 0.0));
        worst = worst.max((r - a).abs());
        if a >= 0.2 {
            worst_rel = worst_rel.max((r / a - 1.0).abs());
        }
    }
    println!("max |R_hemi(alpha(A)) - A| = {worst:.2e}; max relative for A >= 0.2: {worst_rel:.2e}");
    assert!(worst < 2.5e-3, "{worst}");
    assert!(worst_rel < 0.011, "{worst_rel}");
}

/// With anisotropy, Cycles' form is the similarity relation: (1 - alpha) / (1 - g alpha) = s^2, the same s as at g = 0.
#[test]
fn van_de_hulst_anisotropic_form_is_similarity_relation() {
    for g in [-0.5, 0.3, 0.8] {
        for a in [0.1, 0.5, 0.9] {
            let s2 = 1.0 - van_de_hulst_single_scatter_albedo(a, 0.0);
            let alpha = van_de_hulst_single_scatter_albedo(a, g);
            assert!(((1.0 - alpha) / (1.0 - g * alpha) - s2).abs() < 1e-12, "g = {g}, A = {a}");
        }
    }
}

/// The issue's renders: a Base Color made for the Wrenninge fit renders in 5.2 / 5.3 (Van de Hulst) off by -0.9 %
/// (caucasian) to +1.7 % (african). The flat-slab model predicts those extremes within 0.3 % absolute.
#[test]
fn fit_base_color_in_van_de_hulst_matches_rendered_offsets() {
    let offsets = |preset: &str| -> Vec<f64> {
        let ev = material(preset, "5.0", "cycles");
        let m = ev.methods.unwrap().random_walk;
        (0..3).map(|c| flat_albedo(RandomWalkModel::VanDeHulst, m.base_color[c]) / m.expected_albedo[c] - 1.0).collect()
    };
    let caucasian = offsets("caucasian");
    let african = offsets("african");
    println!("caucasian {caucasian:?}, african {african:?}");
    let min = caucasian.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = african.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    assert!((min - -0.009).abs() < 0.003, "caucasian most negative {min}, expected -0.009 +- 0.003");
    assert!((max - 0.017).abs() < 0.003, "african most positive {max}, expected 0.017 +- 0.003");
}

/// 5.2 and later: the Van de Hulst Base Color renders the model's albedo by the flat-slab model, and walks with the
/// same single-scattering albedo as the fit's Base Color (the same medium); Radius x Scale is the 5.0 radius / (4 pi)
/// times the width ratio of the two models.
#[test]
fn random_walk_5_2_radius_convention() {
    for preset in ["caucasian", "asian", "african"] {
        let old = material(preset, "5.0", "cycles").methods.unwrap().random_walk;
        for version in ["5.2", "5.3"] {
            let ev = material(preset, version, "cycles");
            let albedo = ev.diffuse_reflectance_rgb.unwrap();
            let methods = ev.methods.unwrap();
            let new = methods.random_walk;
            for (c, &target) in albedo.iter().enumerate() {
                let rendered = flat_albedo(RandomWalkModel::VanDeHulst, new.base_color[c]);
                assert!((rendered - target).abs() < 1e-10, "{preset} {version} ch {c}: {rendered} vs {target}");
                let alpha_new = van_de_hulst_single_scatter_albedo(new.base_color[c], 0.0);
                let alpha_old = RandomWalkModel::WrenningeFit.single_scatter_albedo(old.base_color[c]);
                assert!((alpha_new - alpha_old).abs() < 1e-8, "{preset} ch {c}: alpha {alpha_new} vs {alpha_old}");
                let ratio = width_factor(RandomWalkModel::VanDeHulst, new.base_color[c])
                    / width_factor(RandomWalkModel::WrenningeFit, old.base_color[c]);
                let want = old.subsurface_radius_mm[c] / (4.0 * PI) * ratio;
                assert!((new.subsurface_radius_mm[c] / want - 1.0).abs() < 1e-9, "{preset} {version} ch {c}");
            }
            // Random Walk (Legacy) in 5.2+ is the 5.0 Random Walk.
            assert_eq!(methods.random_walk_legacy.unwrap(), old, "{preset} {version}");
        }
    }
}

/// The inversion is one root finder for both alpha mappings: both round-trip to 1e-12 and saturate at the same
/// albedo (alpha clamped to 0.999999).
#[test]
fn both_walk_models_round_trip() {
    for model in RandomWalkModel::ALL {
        for i in 1..=95 {
            let t = 0.01 * i as f64;
            let c = base_color_for(model, t);
            assert!(!c.saturated && (flat_albedo(model, c.base_color) - t).abs() < 1e-12, "{model:?} {t}: {c:?}");
        }
        let top = base_color_for(model, 1.0);
        assert!(top.saturated && (top.achieved_albedo - 0.9971).abs() < 1e-4, "{model:?}: {top:?}");
    }
}

/// EEVEE's compensation by hand at albedo (0.8, 0.4, 0.2): A_n = (1, 0.5, 0.25), s = 1.9 - A_n + 3.5 (A_n - 0.8)^2
/// = (1.04, 1.715, 2.70875). Black albedo gives finite radii.
#[test]
fn eevee_compensation_by_hand() {
    let m = eevee_burley([0.8, 0.4, 0.2], [1.0, 2.0, 3.0]);
    for (got, want) in m.subsurface_radius_mm.iter().zip([1.04, 2.0 * 1.715, 3.0 * 2.70875]) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
    assert_eq!(m.base_color, [0.8, 0.4, 0.2]);
    let black = eevee_burley([0.0; 3], [1.0; 3]);
    assert!(black.subsurface_radius_mm.iter().all(|r| r.is_finite() && *r > 0.0), "{black:?}");
    let one_black = eevee_burley([0.5, 0.0, 0.25], [1.0; 3]);
    assert!(one_black.subsurface_radius_mm.iter().all(|r| r.is_finite()), "{one_black:?}");
}

/// The issue's measurement: with the Cycles radius, EEVEE's radius is short by 4-18 % (caucasian) and 4-38 %
/// (african) per channel, i.e. 1 - 1/gain for the compensation's gain s(A_n). Every method maps the same way in
/// EEVEE, Base Color = albedo. The issue measured the paper's (diffusion) materials, whose albedos the gain depends on.
#[test]
fn eevee_radius_gain_matches_issue() {
    let material = |preset: &str, blender: &str, engine: &str| {
        let request = Request {
            target: target(blender, engine),
            transport: spectral_skin::transport::Transport::Diffusion,
            ..Request::new(Outputs::material())
        };
        evaluate(&SkinParams::preset(preset).unwrap(), &request).unwrap()
    };
    for (preset, lo, hi) in [("caucasian", 0.04, 0.18), ("african", 0.04, 0.38)] {
        for version in ["4.5", "5.3"] {
            let cycles = material(preset, version, "cycles").methods.unwrap().burley;
            let ev = material(preset, version, "eevee");
            assert_eq!(ev.target.engine, Engine::Eevee, "{preset} {version}");
            let methods = ev.methods.unwrap();
            let short: Vec<f64> =
                (0..3).map(|c| 1.0 - cycles.subsurface_radius_mm[c] / methods.burley.subsurface_radius_mm[c]).collect();
            let (min, max) = (short.iter().cloned().fold(9.0, f64::min), short.iter().cloned().fold(0.0, f64::max));
            assert!(
                (min - lo).abs() < 0.005 && (max - hi).abs() < 0.005,
                "{preset} {version}: short by {short:?}: min {min} vs {lo}, max {max} vs {hi} (+- 0.005)"
            );
            for (_, p) in methods.iter() {
                assert_eq!(*p, methods.burley, "{preset} {version}");
                assert_eq!(p.base_color, ev.diffuse_reflectance_rgb.unwrap(), "{preset} {version}");
            }
        }
    }
}

/// Cycles Burley is the same in every version: Base Color = albedo, radius = the fit's 4 pi d.
#[test]
fn cycles_burley_is_version_independent() {
    let reference = material("asian", "5.0", "cycles");
    let fit = reference.radius_fit.unwrap();
    for entry in VERSION_TABLE {
        let ev = material("asian", &entry.version.to_string(), "cycles");
        let b = ev.methods.unwrap().burley;
        assert_eq!(b.base_color, ev.diffuse_reflectance_rgb.unwrap(), "Blender {}", entry.version);
        assert_eq!(b.subsurface_radius_mm, fit.map(|f| f.radius_mm), "Blender {}", entry.version);
    }
}

/// The table: every tested version resolves as tested; versions between or past entries resolve to the newest entry
/// below, untested; older than 4.2 and malformed versions are errors naming the input and the supported range.
#[test]
fn version_table_rules() {
    let tested: Vec<String> = VERSION_TABLE.iter().filter(|e| e.tested).map(|e| e.version.to_string()).collect();
    assert_eq!(tested, ["4.2", "4.5", "5.0", "5.2", "5.3"]);
    for v in &tested {
        let t = target(v, "cycles");
        assert!(t.info().tested, "{v}: {:?}", t.info());
        assert_eq!(t.blender.entry().version.to_string(), *v);
    }
    // EEVEE is render-tested from 4.5 on (4.2's EEVEE subsurface does not repeat under llvmpipe).
    for v in &tested {
        assert_eq!(target(v, "eevee").info().tested, v != "4.2", "{v} eevee");
    }
    // Each untested target says why, in the words every front shows (4.2's EEVEE was told it was "newer than the
    // versions tested").
    for (v, engine, reason) in [
        ("4.2", "eevee", "EEVEE in Blender 4.2 was not validated by renders"),
        ("4.3", "cycles", "Blender 4.3 was not tested: it uses the behaviour of Blender 4.2"),
        ("5.9", "eevee", "Blender 5.9 is newer than the versions Spectral Skin was tested with (up to 5.3)"),
    ] {
        let info = target(v, engine).info();
        let said = info.untested_reason().unwrap_or_default();
        assert!(said.starts_with(reason), "{v} {engine}: {said:?}");
        let json = serde_json::to_value(info).unwrap();
        assert_eq!(json["untested_reason"].as_str(), Some(said.as_str()), "{json}");
    }
    let json = serde_json::to_value(target("5.3", "cycles").info()).unwrap();
    assert!(target("5.3", "cycles").untested_reason().is_none() && json.get("untested_reason").is_none(), "{json}");
    for (v, resolves_to) in [("4.3", "4.2"), ("5.1", "5.0"), ("5.9", "5.3"), ("6.0", "5.3"), ("5.2.3", "5.2")] {
        let t = target(v, "cycles");
        assert_eq!(t.blender.entry().version.to_string(), resolves_to, "{v}");
        assert_eq!(t.info().tested, v == "5.2.3", "{v}");
    }
    let newest: Vec<_> = target("5.9", "cycles").methods().collect();
    assert_eq!(newest, SubsurfaceMethod::ALL);
    for bad in ["4.1", "3.6", "2.93"] {
        let e = bad.parse::<BlenderVersion>().unwrap_err().to_string();
        assert!(e.contains(bad) && e.contains("4.2 and newer") && e.contains("5.3"), "{bad}: {e}");
    }
    for bad in ["", "5", "five", "5.x", "5.2.3.1", "-5.2"] {
        let e = bad.parse::<BlenderVersion>().unwrap_err().to_string();
        assert!(e.contains("MAJOR.MINOR") && e.contains(&format!("{bad:?}")), "{bad}: {e}");
    }
    let v523 = BlenderVersion::from_parts(&[5, 2, 3]);
    assert!(v523.is_ok(), "5.2.3: {v523:?}");
    let v410 = BlenderVersion::from_parts(&[4, 1, 0]);
    assert!(v410.is_err(), "4.1.0: {v410:?}");
    let e = Target::parse("5.3", "workbench").unwrap_err().to_string();
    assert!(e.contains("cycles, eevee"), "workbench: {e}");
}

/// Random Walk (Legacy) exists from 5.2 on; asking for it in 5.0 is a clear error, in evaluate's methods it is absent.
#[test]
fn legacy_method_only_from_5_2() {
    let e = target("5.0", "cycles").method_entry(SubsurfaceMethod::RandomWalkLegacy).unwrap_err().to_string();
    assert!(e.contains("random_walk_legacy") && e.contains("5.0") && e.contains("random_walk_skin"), "{e}");
    let legacy = target("5.2", "eevee").method_entry(SubsurfaceMethod::RandomWalkLegacy);
    assert!(legacy.is_ok(), "5.2 eevee: {legacy:?}");
    let json = serde_json::to_value(material("caucasian", "4.2", "cycles")).unwrap();
    let keys: Vec<&String> = json["methods"].as_object().unwrap().keys().collect();
    assert_eq!(keys, ["burley", "random_walk", "random_walk_skin"]);
    let json = serde_json::to_value(material("caucasian", "5.3", "cycles")).unwrap();
    assert_eq!(json["methods"].as_object().unwrap().len(), 4);
    assert_eq!(json["target"], serde_json::json!({"blender": "5.3", "engine": "cycles", "tested": true}));
}

/// The engine ids per version (`scene.render.engine`).
#[test]
fn engine_ids() {
    for (v, eevee) in [
        ("4.2", "BLENDER_EEVEE_NEXT"),
        ("4.5", "BLENDER_EEVEE_NEXT"),
        ("5.0", "BLENDER_EEVEE"),
        ("5.3", "BLENDER_EEVEE"),
    ] {
        let version: BlenderVersion = v.parse().unwrap();
        assert_eq!(Engine::Eevee.blender_id(version), eevee, "{v}");
        assert_eq!(Engine::Cycles.blender_id(version), "CYCLES", "{v}");
    }
}

/// The width factors reproduce the edge renders in `docs/data/random_walk_width.json` (read here on its own, not
/// through the core's table): at each measured Base Color, 1 / width factor is the rendered d / mean free path.
#[test]
fn width_factors_reproduce_the_edge_renders() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/data/random_walk_width.json"))
        .expect("calibration file");
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut seen = 0;
    for entry in json["entries"].as_array().unwrap() {
        let (blender, method) = (entry["blender"].as_str().unwrap(), entry["method"].as_str().unwrap());
        let factor: fn(f64) -> f64 = match (blender, method) {
            ("5.0", "RANDOM_WALK") => |a| width_factor(RandomWalkModel::WrenningeFit, a),
            ("5.3", "RANDOM_WALK") => |a| width_factor(RandomWalkModel::VanDeHulst, a),
            ("5.0", "RANDOM_WALK_SKIN") => skin_width_factor,
            _ => continue,
        };
        for case in entry["cases"].as_array().unwrap() {
            let a = case["albedo"].as_f64().unwrap();
            let k = case["d_over_mfp"].as_f64().unwrap();
            assert!((1.0 / factor(a) / k - 1.0).abs() < 1e-9, "{blender} {method} A = {a}: {} vs {k}", 1.0 / factor(a));
            seen += 1;
        }
    }
    assert_eq!(seen, 27);
}
