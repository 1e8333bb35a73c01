//! Issue 20, item 2: the transport is a choice of every Rust front (`Request`, `Accuracy::streams`,
//! `layered_reflectance_with`, the fits' options, the cache keys), reported in every result; `Transport::Diffusion`
//! reproduces the multipole's values bit for bit; `Transport::AddingDoubling` (the default) takes each wavelength's
//! total from the exact solver and its profile's shape from the exact shapes' table, and
//! `Transport::AddingDoublingDiffusionShape` scales the multipole's profile to the exact total.

use spectral_skin::diffusion::{clamped_reflectance_profiles, Combination, LayerStack, MultipoleTerms};
use spectral_skin::evaluate::{Accuracy, AccuracyLevel, Prepared};
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::inverse::albedo::{albedo_table_key, AlbedoFitOptions};
use spectral_skin::inverse::{fit_spectrum, FitOptions};
use spectral_skin::maps::lut::{cache_key, TableResolution};
use spectral_skin::reflectance::{layered_reflectance_with, LayeredOptions, ProfileShape};
use spectral_skin::skin::params::EXTENDED_DEFAULTS;
use spectral_skin::skin::skin_layers;
use spectral_skin::transport::profile_table::exact_shape;
use spectral_skin::transport::total_table::TotalTable;
use spectral_skin::transport::{
    total_diffuse_reflectance, ExactTotals, Transport, ALL_TRANSPORTS, DEFAULT_STREAMS, STREAMS_RANGE,
};
use spectral_skin::{evaluate, Outputs, Request, SkinParams, PRESETS};

fn request(transport: Transport, outputs: Outputs) -> Request {
    Request { transport, ..Request::new(outputs) }
}

fn everything() -> Outputs {
    Outputs { albedo: true, radius: true, spectrum: true, profile_spectral: true, ..Outputs::default() }
}

/// The multipole's own totals and clamped profiles of `params` on `request`'s grid, from the diffusion module's public
/// pieces: what every output was before the transport existed.
fn multipole(params: &SkinParams, request: &Request) -> (Vec<f64>, Vec<Vec<f64>>) {
    let prepared = Prepared::new(request).unwrap();
    let stacks = prepared.stacks(params).unwrap();
    let acc = &request.accuracy;
    let totals = stacks.iter().map(|s| s.reflectance_hat(0.0, request.combination, acc.multipole_terms)).collect();
    let radii = acc.profile_grid.radii_mm();
    let profiles =
        clamped_reflectance_profiles(&stacks, &radii, request.combination, acc.multipole_terms, &acc.hankel).per_mm2;
    (totals, profiles)
}

/// `Transport::Diffusion` is the multipole, bit for bit: every wavelength's total and profile value.
#[test]
fn diffusion_reproduces_the_multipole_bit_for_bit() {
    for preset in PRESETS {
        let r = request(Transport::Diffusion, everything());
        let ev = evaluate(&preset.params, &r).unwrap();
        let (totals, profiles) = multipole(&preset.params, &r);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(ev.spectral_reflectance.as_ref().unwrap()), bits(&totals), "{}", preset.name);
        let spectral = ev.profile.as_ref().unwrap().spectral_per_mm2.as_ref().unwrap();
        for (got, want) in spectral.iter().zip(&profiles) {
            assert_eq!(bits(got), bits(want), "{}", preset.name);
        }
        assert_eq!(ev.transport, Transport::Diffusion, "{}", preset.name);
        assert_eq!(ev.work.transport_solves, 0, "{}", preset.name);
    }
}

/// The exact-total transports with `ExactTotals::Solve`: each total is the exact solver's at the request's streams and
/// the work counts one solve per wavelength; the profile is the total times the exact shape of the stack (`AddingDoubling`, which
/// reports `profile_shape` "exact") or the multipole's profile scaled by total / multipole total
/// (`AddingDoublingDiffusionShape`, "multipole").
#[test]
fn exact_totals_carry_their_profile_shape() {
    let params = SkinParams::preset("african").unwrap();
    for transport in [Transport::AddingDoubling, Transport::AddingDoublingDiffusionShape] {
        for streams in [4, DEFAULT_STREAMS, 16] {
            let mut r = request(transport, everything());
            r.accuracy.streams = streams;
            r.accuracy.exact_totals = ExactTotals::Solve;
            let ev = evaluate(&params, &r).unwrap();
            assert_eq!(ev.transport, transport, "{streams} streams");
            assert_eq!(ev.work.transport_table_lookups, 0, "{streams} streams");
            assert_eq!(ev.accuracy.streams, streams);
            let wavelengths = ev.wavelengths_nm.as_ref().unwrap();
            assert_eq!(ev.work.transport_solves, wavelengths.len(), "{streams} streams");
            let profile = ev.profile.as_ref().unwrap();
            let expected_shape = if transport.exact_shape() { "exact" } else { "multipole" };
            assert_eq!(ev.profile_shape, Some(expected_shape), "{transport:?}");
            let (multipole_totals, multipole_profiles) = multipole(&params, &r);
            let spectral = profile.spectral_per_mm2.as_ref().unwrap();
            for (k, &w) in wavelengths.iter().enumerate() {
                let layers = skin_layers(&params, &r.model, w);
                let exact = total_diffuse_reflectance(&layers, streams).unwrap();
                assert_eq!(ev.spectral_reflectance.as_ref().unwrap()[k].to_bits(), exact.to_bits(), "{w} nm");
                let want: Vec<f64> = if transport.exact_shape() {
                    let shape = exact_shape(&layers).expect("the table holds the skin's stacks");
                    profile.radii_mm.iter().map(|&r| exact * shape.normalized_profile_per_mm2(r)).collect()
                } else {
                    let scale = exact / multipole_totals[k];
                    multipole_profiles[k].iter().map(|p| p * scale).collect()
                };
                for (got, want) in spectral[k].iter().zip(&want) {
                    assert!((got - want).abs() <= 1e-15 * want.abs(), "{transport:?} {w} nm: {got} vs {want}");
                }
            }
        }
    }
}

/// With `ExactTotals::Table` (the default) every skin total is read from the shipped table, none solved: each equals
/// the table's value of that wavelength's stack, and the colour is within the table's error of fresh 32-stream solves.
#[test]
fn default_totals_are_read_from_the_table() {
    assert_eq!(Accuracy::default().exact_totals, ExactTotals::Table);
    assert_eq!(AccuracyLevel::Reference.accuracy().exact_totals, ExactTotals::Solve);
    let table = TotalTable::shipped();
    for preset in PRESETS {
        let r = request(Transport::AddingDoubling, everything());
        let ev = evaluate(&preset.params, &r).unwrap();
        let wavelengths = ev.wavelengths_nm.as_ref().unwrap();
        assert_eq!(
            (ev.work.transport_solves, ev.work.transport_table_lookups),
            (0, wavelengths.len()),
            "{}",
            preset.name
        );
        let mut solved = r;
        solved.accuracy.exact_totals = ExactTotals::Solve;
        solved.accuracy.streams = table.streams();
        let reference = evaluate(&preset.params, &solved).unwrap();
        assert_eq!(reference.work.transport_solves, wavelengths.len());
        for (k, &w) in wavelengths.iter().enumerate() {
            let layers = skin_layers(&preset.params, &r.model, w);
            let held = table.total_of(&layers).expect("skin's stacks are in the table");
            let got = ev.spectral_reflectance.as_ref().unwrap()[k];
            assert_eq!(got.to_bits(), held.to_bits(), "{} {w} nm", preset.name);
            let fresh = reference.spectral_reflectance.as_ref().unwrap()[k];
            assert!((got - fresh).abs() <= 1e-4 * fresh.max(1e-3), "{} {w} nm: {got} vs {fresh}", preset.name);
        }
    }
}

/// The default is adding-doubling everywhere, and a request or accuracy written before the choice existed reads as the
/// default; the JSON always names the transport and the streams.
#[test]
fn default_and_json() {
    assert_eq!(Transport::default(), Transport::AddingDoubling);
    assert_eq!(ALL_TRANSPORTS[0], Transport::default());
    assert_eq!(Request::default().transport, Transport::AddingDoubling);
    assert_eq!(LayeredOptions::default().transport, Transport::AddingDoubling);
    assert_eq!(AlbedoFitOptions::default().transport, Transport::AddingDoubling);
    assert_eq!(FitOptions::default().request.transport, Transport::AddingDoubling);

    let mut json = serde_json::to_value(Request::default()).unwrap();
    assert_eq!(json["transport"], "adding_doubling");
    assert_eq!(json["accuracy"]["streams"], DEFAULT_STREAMS);
    json.as_object_mut().unwrap().remove("transport");
    json["accuracy"].as_object_mut().unwrap().remove("streams");
    let old: Request = serde_json::from_value(json).unwrap();
    assert_eq!(old, Request::default());

    let diffusion = request(Transport::Diffusion, Outputs::material());
    let back: Request = serde_json::from_str(&serde_json::to_string(&diffusion).unwrap()).unwrap();
    assert_eq!(back, diffusion);

    let ev = evaluate(&SkinParams::preset("asian").unwrap(), &diffusion).unwrap();
    let j = serde_json::to_value(&ev).unwrap();
    assert_eq!(j["transport"], "diffusion");
    assert_eq!(j["accuracy"]["streams"], DEFAULT_STREAMS);
    assert_eq!(j["work"]["transport_solves"], 0);
}

/// The levels' streams: draft 4, default `DEFAULT_STREAMS`, reference 32; `refined()` doubles them up to the range.
#[test]
fn streams_per_level() {
    assert_eq!(AccuracyLevel::Draft.accuracy().streams, 4);
    assert_eq!(AccuracyLevel::Default.accuracy().streams, DEFAULT_STREAMS);
    assert_eq!(AccuracyLevel::Reference.accuracy().streams, 32);
    assert_eq!(Accuracy::reference().refined().streams, 64);
    assert_eq!(Accuracy { streams: 48, ..Accuracy::default() }.refined().streams, STREAMS_RANGE.1);
    assert_eq!(Accuracy::default().refined().streams, 2 * DEFAULT_STREAMS);
}

/// Streams outside `STREAMS_RANGE` or odd are an error naming `streams` and the range, on every Rust front.
#[test]
fn bad_streams_are_clear_errors() {
    let (lo, hi) = STREAMS_RANGE;
    for bad in [0, lo - 1, 7, hi + 1, 1000] {
        let named = |e: String| {
            assert!(
                e.contains("streams") && e.contains(&format!("[{lo}, {hi}]")) && e.contains(&bad.to_string()),
                "{e}"
            )
        };
        let mut r = Request::new(Outputs::material());
        r.accuracy.streams = bad;
        named(Prepared::new(&r).unwrap_err().to_string());
        named(evaluate(&SkinParams::preset("asian").unwrap(), &r).unwrap_err().to_string());
        let layers = skin_layers(&SkinParams::preset("asian").unwrap(), &r.model, 550.0);
        let options = LayeredOptions { streams: bad, ..LayeredOptions::default() };
        named(layered_reflectance_with(&layers, &[1.0], &options).unwrap_err().to_string());
        named(AlbedoFitOptions { streams: bad, ..AlbedoFitOptions::default() }.validated().unwrap_err().to_string());
        let mut fit = FitOptions::default();
        fit.request.accuracy.streams = bad;
        let wavelengths: Vec<f64> = (0..9).map(|i| 400.0 + 40.0 * i as f64).collect();
        let rising: Vec<f64> = (0..9).map(|i| 0.2 + 0.02 * i as f64).collect();
        named(fit_spectrum(&wavelengths, &rising, &fit).unwrap_err().to_string());
    }
    // Diffusion does not use the streams, but a bad value is still refused (one rule for the knob, as `Accuracy`'s).
    let options = LayeredOptions { transport: Transport::Diffusion, streams: 0, ..LayeredOptions::default() };
    let layers = skin_layers(&SkinParams::preset("asian").unwrap(), &Default::default(), 550.0);
    let e = layered_reflectance_with(&layers, &[1.0], &options).unwrap_err().to_string();
    assert!(e.contains("streams"), "{e}");
}

/// The material-table cache key (and so the shader table's) and the albedo fit's table key differ by transport and
/// by streams.
#[test]
fn cache_keys_differ_by_transport_and_streams() {
    let resolution = TableResolution::default();
    let key = |transport: Transport, streams: usize| {
        let mut r = request(transport, Outputs::material());
        r.accuracy.streams = streams;
        cache_key(&Prepared::new(&r).unwrap(), SubsurfaceMethod::Burley, resolution, true, EXTENDED_DEFAULTS)
    };
    let base = key(Transport::AddingDoubling, DEFAULT_STREAMS);
    assert_ne!(base, key(Transport::Diffusion, DEFAULT_STREAMS));
    assert_ne!(base, key(Transport::AddingDoubling, 16));
    assert_eq!(base, key(Transport::AddingDoubling, DEFAULT_STREAMS));

    let albedo = |transport: Transport, streams: usize| {
        albedo_table_key(&AlbedoFitOptions { transport, streams, ..AlbedoFitOptions::default() })
    };
    let base = albedo(Transport::AddingDoubling, DEFAULT_STREAMS);
    assert_ne!(base, albedo(Transport::Diffusion, DEFAULT_STREAMS));
    assert_ne!(base, albedo(Transport::AddingDoubling, 16));
}

/// The fits invert the model of their options' transport: the albedo fit's forward evaluation is the request's.
#[test]
fn fits_use_their_transport() {
    for transport in ALL_TRANSPORTS {
        let options = AlbedoFitOptions { transport, streams: 16, ..AlbedoFitOptions::default() };
        let prepared = options.prepared().unwrap();
        assert_eq!(prepared.request().transport, transport);
        assert_eq!(prepared.request().accuracy.streams, 16, "{transport:?}");
        let params = SkinParams::preset("caucasian").unwrap();
        let direct = evaluate(
            &params,
            &Request { outputs: Outputs { albedo: true, ..Outputs::default() }, ..*prepared.request() },
        )
        .unwrap()
        .diffuse_reflectance_rgb
        .unwrap();
        assert_eq!(prepared.albedo(&params).unwrap(), direct, "{transport:?}");
    }
}

/// `layered_reflectance_with`: diffusion is the multipole stack's own total and profile; the exact-total transports
/// the exact total with the multipole profile scaled to it (`AddingDoublingDiffusionShape`) or the exact shape (the
/// default), each naming its shape.
#[test]
fn layered_reflectance_takes_the_transport() {
    let params = SkinParams::preset("african").unwrap();
    let layers = skin_layers(&params, &Default::default(), 450.0);
    let radii = [0.0, 0.1, 1.0];
    let with = |transport| LayeredOptions { transport, ..LayeredOptions::default() };
    let d = layered_reflectance_with(&layers, &radii, &with(Transport::Diffusion)).unwrap();
    let stack = LayerStack::new(&layers).unwrap();
    assert_eq!(d.total.to_bits(), stack.reflectance_hat(0.0, Combination::Directional, MultipoleTerms::All).to_bits());
    assert_eq!(d.shape, ProfileShape::Multipole);
    let exact_total = total_diffuse_reflectance(&layers, DEFAULT_STREAMS).unwrap();
    let scaled = layered_reflectance_with(&layers, &radii, &with(Transport::AddingDoublingDiffusionShape)).unwrap();
    assert_eq!(scaled.total.to_bits(), exact_total.to_bits());
    assert_eq!(scaled.shape, ProfileShape::Multipole);
    for (x, y) in scaled.profile_per_mm2.iter().zip(&d.profile_per_mm2) {
        let want = y * (scaled.total / d.total);
        assert!((x - want).abs() <= 1e-15 * want, "{x} vs {want}");
    }
    let a = layered_reflectance_with(&layers, &radii, &LayeredOptions::default()).unwrap();
    assert_eq!(a.total.to_bits(), exact_total.to_bits());
    assert_eq!(a.shape, ProfileShape::Exact);
    let shape = exact_shape(&layers).unwrap();
    for (x, &r) in a.profile_per_mm2.iter().zip(&radii) {
        let want = exact_total * shape.normalized_profile_per_mm2(r);
        assert!((x - want).abs() <= 1e-15 * want, "{x} vs {want} at {r} mm");
    }
}
