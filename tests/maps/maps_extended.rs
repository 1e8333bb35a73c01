//! The extended physiology (epidermis thickness, baseline absorption scale, blood oxygenation) through the map
//! pipeline: defaults change nothing, a constant is baked into the table (and its cache key), a varying map gives every
//! texel `evaluate`'s value, bad values are named, extra channels and single-parameter maps are read.

use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::example::face_params;
use spectral_skin::maps::io::{
    read_params, write_channels_exr, ExrOptions, ParamImage, ParamInputs, ParamSource, Plane, EXTENDED_CHANNELS,
};
use spectral_skin::maps::lut::{cache_key, MaterialTable, TableResolution};
use spectral_skin::maps::pipeline::{check_planes, run_maps, Strategy, SIDECAR_FILE};
use spectral_skin::maps::shader_table::{measure_shader_error, ShaderTable};
use spectral_skin::maps::thickness_tables::THICKNESS_NODES_MM;
use spectral_skin::maps::{compute_maps, MapSettings, StrategyChoice};
use spectral_skin::skin::params::EXTENDED_DEFAULTS;
use spectral_skin::surface::lobes::SurfaceModel;
use spectral_skin::transport::profile_table::ProfileTable;
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

/// The bound on the thickness stack's radius (docs/maps-performance.md, "A varying epidermis thickness": measured
/// 7.6 %, at a thin epidermis (0.05-0.07 mm) under much melanin, red channel, where the fitted radius wiggles between
/// nodes 0.015 mm apart).
const RADIUS_BOUND: f64 = 0.10;

fn with_extended(mut image: ParamImage, extended: [Plane; 3]) -> ParamImage {
    image.extended = extended;
    image
}

fn constant(values: [f32; 3]) -> [Plane; 3] {
    values.map(Plane::Constant)
}

/// Base Color and radius of `evaluate` for these parameters and the default request (Burley), as f32.
fn expected(p: &SkinParams) -> ([f32; 3], [f32; 3]) {
    let ev = evaluate(p, &Request::new(Outputs::material())).unwrap();
    let m = *ev.methods.unwrap().get(SubsurfaceMethod::Burley).unwrap();
    (m.base_color.map(|v| v as f32), m.subsurface_radius_mm.map(|v| v as f32))
}

/// The four and the extended physiology of texel `i`, widened and rounded into range as the pipeline does.
fn texel_params(image: &ParamImage, i: usize) -> SkinParams {
    let v = |p: usize| image.plane(p).value(i) as f64;
    let ranges = spectral_skin::skin::params::PARAMS.map(|s| s.range());
    SkinParams::from_values(std::array::from_fn(|p| if p == 3 { 0.3 } else { v(p).clamp(ranges[p].0, ranges[p].1) }))
        .unwrap()
}

/// The extended physiology at its defaults, given as constants or as maps that hold the default everywhere, gives
/// bit-identical maps to the image without it, by every strategy (constant, distinct tuples, table).
#[test]
fn defaults_change_nothing() {
    let face = face_params(64);
    let n = face.texel_count();
    let settings = MapSettings::default();
    let plain = compute_maps(&face, &settings, None).unwrap();
    let defaults = EXTENDED_DEFAULTS.map(|v| Plane::Texels(vec![v as f32; n]));
    let given = compute_maps(&with_extended(face.clone(), defaults), &settings, None).unwrap();
    assert!(matches!(plain.report.strategy, Strategy::Table { .. }), "{:?}", plain.report.strategy);
    assert!(matches!(given.report.strategy, Strategy::Table { .. }), "{:?}", given.report.strategy);
    assert_eq!(plain.base_color, given.base_color);
    assert_eq!(plain.radius_mm, given.radius_mm);
    // The report names the extended physiology as constant, at the defaults.
    for (name, value) in EXTENDED_CHANNELS.iter().zip(EXTENDED_DEFAULTS) {
        assert!(given.report.constant_parameters.contains(name), "{name}");
        assert_eq!(given.report.constant_values[name], value as f32 as f64, "{name}");
    }
}

/// The paper's model keeps the cache key text it had before the extended physiology existed (FNV-1a of the same
/// text, computed here independently), followed by the shipped profile table's id, since the radius comes from its
/// exact shapes; any other value has its own key. The surface model, which no table holds, does not change it: the
/// default (measured) request has the paper's key.
#[test]
fn cache_key_is_unchanged_for_the_paper_and_differs_otherwise() {
    let request = Request { surface: SurfaceModel::Paper, ..Request::new(Outputs::material()) };
    let prepared = Prepared::new(&request).unwrap();
    let measured = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let resolution = TableResolution::default();
    let method = SubsurfaceMethod::Burley;
    let text = format!(
        "{}|model {}|{}|{}|{:?}|shapes {}",
        env!("CARGO_PKG_VERSION"),
        spectral_skin::MODEL_VERSION,
        serde_json::to_string(&request).unwrap(),
        method.name(),
        resolution,
        ProfileTable::shipped().id()
    );
    // FNV-1a, 64 bit (offset basis and prime of Fowler, Noll & Vo).
    let fnv = text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    assert_eq!(cache_key(&prepared, method, resolution, true, EXTENDED_DEFAULTS), fnv);
    assert_eq!(cache_key(&measured, method, resolution, true, EXTENDED_DEFAULTS), fnv);
    let mut keys = vec![fnv];
    for k in 0..3 {
        let mut e = EXTENDED_DEFAULTS;
        e[k] = if k == 0 { 0.08 } else { 0.5 };
        keys.push(cache_key(&prepared, method, resolution, true, e));
        // The next double is another table.
        e[k] = f64::from_bits(e[k].to_bits() + 1);
        keys.push(cache_key(&prepared, method, resolution, true, e));
    }
    let mut unique = keys.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), keys.len(), "{keys:x?}");
}

/// A table cached for the defaults is not reused for another thickness (built afresh, other values), and the one for
/// that thickness is then reused.
#[test]
fn cached_table_is_not_reused_for_other_extended_values() {
    let dir = tempfile::tempdir().unwrap();
    let prepared = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let small = TableResolution { melanin: 3, melanin_blend: 2, hemoglobin: 3 };
    let build = |e: [f64; 3]| {
        let cancel = std::sync::atomic::AtomicBool::new(false);
        MaterialTable::load_or_build_outputs(
            &prepared,
            SubsurfaceMethod::Burley,
            small,
            true,
            e,
            Some(dir.path()),
            &cancel,
            None,
        )
        .unwrap()
    };
    let thin = [0.08, 1.0, 0.75];
    let (paper, cached) = build(EXTENDED_DEFAULTS);
    assert!(!cached, "{EXTENDED_DEFAULTS:?}: the first build came from an empty cache");
    let (other, cached) = build(thin);
    assert!(!cached, "a table of the paper's thickness was reused for {thin:?}");
    assert_eq!(other.extended(), thin);
    assert_ne!(paper.node_log_method(1, 1, 1), other.node_log_method(1, 1, 1));
    let (again, cached) = build(thin);
    assert!(cached, "{thin:?}: the second build was not read from the cache");
    assert_eq!(again.node_log_method(1, 1, 1), other.node_log_method(1, 1, 1));
    assert_eq!(again.extended(), thin);
}

/// A non-default constant: the constant and distinct-tuple strategies give `evaluate`'s values exactly; the table
/// (built with the constant baked in) is within its error bound of them, and far from the paper's thickness.
#[test]
fn a_constant_gives_evaluates_values() {
    let thin = [0.08f32, 2.0, 0.9];
    let n = 24 * 24;
    let mask: Vec<f32> = (0..n).map(|i| [0.01, 0.2, 0.4][(i / 24) % 3]).collect();
    let masked = ParamImage::new(
        24,
        24,
        [Plane::Texels(mask), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)],
    );
    let settings = MapSettings::default();
    let r = compute_maps(&with_extended(masked.clone(), constant(thin)), &settings, None).unwrap();
    assert_eq!(r.report.strategy, Strategy::DistinctTuples { tuples: 3 });
    let image = with_extended(masked, constant(thin));
    for i in [0, 24, 48, n - 1] {
        let (c, rad) = expected(&texel_params(&image, i));
        let base_color = r.base_color.as_ref().unwrap();
        let radius = r.radius_mm.as_ref().unwrap();
        assert_eq!([base_color[0][i], base_color[1][i], base_color[2][i]], c, "texel {i}");
        assert_eq!([radius[0][i], radius[1][i], radius[2][i]], rad, "texel {i}");
    }
    assert_eq!(r.report.constant_values["epidermis_thickness_mm"], 0.08f32 as f64);

    // The table: every texel within 1 % (Base Color) and 2 % (radius) of evaluate. The default resolution was chosen
    // for the paper's model (0.5 % and 1 %); at this thin epidermis and doubled baseline absorption its check
    // measured 0.61 % and 1.6 % (the table interpolates a steeper function).
    let face = with_extended(face_params(64), constant(thin));
    let r = compute_maps(&face, &settings, None).unwrap();
    let Strategy::Table { measured_error: Some(err), .. } = r.report.strategy else {
        panic!("{:?}", r.report.strategy)
    };
    println!("table with extended {thin:?}: {err:?}");
    assert!(err.max_base_color_relative < 0.01 && err.max_radius_relative < 0.02, "{err:?}");
    let paper = compute_maps(&face_params(64), &settings, None).unwrap();
    let mut far = 0.0f32;
    for i in (0..face.texel_count()).step_by(97) {
        let (c, rad) = expected(&texel_params(&face, i));
        for k in 0..3 {
            let got = r.base_color.as_ref().unwrap()[k][i];
            assert!(((got - c[k]) / c[k]).abs() < 0.01, "texel {i}: {got} vs {}", c[k]);
            let got = r.radius_mm.as_ref().unwrap()[k][i];
            assert!(((got - rad[k]) / rad[k]).abs() < 0.02, "texel {i}: {got} vs {}", rad[k]);
            let p = paper.base_color.as_ref().unwrap()[k][i];
            far = far.max(((p - c[k]) / c[k]).abs());
        }
    }
    // The extended values matter far beyond the table's error (else the test above could not fail).
    assert!(far > 0.05, "{far}");
}

/// A thickness map that varies: a few values go by distinct tuples, many (over 2048 tuples) by direct evaluation of
/// every texel; each texel is what `evaluate` gives for its own thickness.
#[test]
fn a_varying_thickness_map_gives_each_texel_evaluates_value() {
    let (w, h) = (4, 3);
    let thickness: Vec<f32> = (0..w * h).map(|i| 0.02 + 0.04 * i as f32).collect();
    let img = with_extended(
        ParamImage::new(
            w,
            h,
            [Plane::Constant(0.1), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)],
        ),
        [Plane::Texels(thickness), Plane::Constant(1.0), Plane::Constant(0.75)],
    );
    let r = compute_maps(&img, &MapSettings::default(), None).unwrap();
    assert_eq!(r.report.strategy, Strategy::DistinctTuples { tuples: w * h });
    assert!(!r.report.constant_parameters.contains(&"epidermis_thickness_mm"), "{:?}", r.report.constant_parameters);
    for i in 0..w * h {
        let (c, rad) = expected(&texel_params(&img, i));
        assert_eq!(r.base_color.as_ref().unwrap()[0][i], c[0], "texel {i}");
        assert_eq!(r.radius_mm.as_ref().unwrap()[2][i], rad[2], "texel {i}");
    }

    // Over MAX_DISTINCT_TUPLES distinct thicknesses with a varying melanin: the stack of tables over thickness (albedo
    // only, to keep the test short), each texel within 1 % of `evaluate` for its own thickness (the 3-D table's own
    // bound), and its measured error says so; asked for exact, direct evaluation per texel, `evaluate`'s values bit for bit.
    let (w, h) = (64, 33);
    let n = w * h;
    let melanin: Vec<f32> = (0..n).map(|i| 0.5 * (i % 97) as f32 / 96.0).collect();
    let thickness: Vec<f32> = (0..n).map(|i| 0.01 + 0.49 * i as f32 / (n - 1) as f32).collect();
    let img = with_extended(
        ParamImage::new(
            w,
            h,
            [Plane::Texels(melanin), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)],
        ),
        [Plane::Texels(thickness), Plane::Constant(1.0), Plane::Constant(0.75)],
    );
    let request = Request::new(Outputs { albedo: true, ..Outputs::default() });
    let settings = MapSettings { request, ..MapSettings::default() };
    let stacked = compute_maps(&img, &settings, None).unwrap();
    let Strategy::ThicknessTables { tables, max_base_color_relative, check_samples, .. } = stacked.report.strategy
    else {
        panic!("{:?}", stacked.report.strategy)
    };
    assert_eq!(tables, THICKNESS_NODES_MM.len(), "the thickness spans every node");
    assert!(check_samples > 0 && max_base_color_relative < 0.01, "{:?}", stacked.report.strategy);
    let mut worst: f64 = 0.0;
    for i in (0..n).step_by(7) {
        let ev = evaluate(&texel_params(&img, i), &Request::new(Outputs::material())).unwrap();
        let albedo = ev.diffuse_reflectance_rgb.unwrap();
        for (plane, expected) in stacked.base_color.as_ref().unwrap().iter().zip(albedo) {
            worst = worst.max((plane[i] as f64 / expected - 1.0).abs());
        }
    }
    println!("thickness stack: worst relative error {worst:.2e} over every 7th texel; {:?}", stacked.report.strategy);
    assert!(worst < 0.01, "worst relative error {worst}");
    let settings = MapSettings { strategy: StrategyChoice::Exact, ..settings };
    let r = compute_maps(&img, &settings, None).unwrap();
    assert_eq!(r.report.strategy, Strategy::Exact { evaluations: n });
    assert_eq!(r.report.work.table_lookups, 0);
    for i in (0..n).step_by(131) {
        let ev = evaluate(&texel_params(&img, i), &Request::new(Outputs::material())).unwrap();
        let albedo = ev.diffuse_reflectance_rgb.unwrap();
        let got: Vec<f32> = r.base_color.as_ref().unwrap().iter().map(|plane| plane[i]).collect();
        assert_eq!(got, albedo.map(|v| v as f32), "texel {i}");
    }
}

/// The radius of the stack over thickness (the weaker output: the Burley radius fitted to each texel's profile is
/// not smooth in thickness, a few per cent of wiggle between the nodes) against `evaluate` for each texel's own
/// thickness, over the range artists paint (0.04 to 0.42 mm) and every melanin: the worst texel is within the bound,
/// and so is the error the pipeline measures on 64 of the map's own texels and reports (smaller: fewer texels).
#[test]
fn a_varying_thickness_maps_radius_is_within_its_stated_bound() {
    let (w, h) = (64, 33);
    let n = w * h;
    let melanin: Vec<f32> = (0..n).map(|i| 0.005 + 0.495 * (i % 89) as f32 / 88.0).collect();
    let thickness: Vec<f32> = (0..n).map(|i| 0.04 + 0.38 * i as f32 / (n - 1) as f32).collect();
    let img = with_extended(
        ParamImage::new(
            w,
            h,
            [Plane::Texels(melanin), Plane::Constant(0.6), Plane::Constant(0.03), Plane::Constant(0.3)],
        ),
        [Plane::Texels(thickness), Plane::Constant(1.0), Plane::Constant(0.75)],
    );
    let stacked = compute_maps(&img, &MapSettings::default(), None).unwrap();
    let Strategy::ThicknessTables { max_radius_relative, max_base_color_relative, .. } = stacked.report.strategy else {
        panic!("{:?}", stacked.report.strategy)
    };
    let (mut worst_radius, mut worst_color): (f64, f64) = (0.0, 0.0);
    for i in (0..n).step_by(5) {
        let (color, radius) = expected(&texel_params(&img, i));
        for c in 0..3 {
            worst_color = worst_color.max((stacked.base_color.as_ref().unwrap()[c][i] / color[c] - 1.0).abs() as f64);
            worst_radius = worst_radius.max((stacked.radius_mm.as_ref().unwrap()[c][i] / radius[c] - 1.0).abs() as f64);
        }
    }
    println!(
        "thickness stack with the radius: worst relative error over every 5th texel: Base Color {worst_color:.2e}, \
         radius {worst_radius:.2e}; reported (the pipeline's own check) {max_base_color_relative:.2e} / \
         {max_radius_relative:.2e}"
    );
    assert!(worst_color < 0.01, "Base Color {worst_color}");
    assert!(worst_radius < RADIUS_BOUND, "radius {worst_radius}");
    assert!(max_radius_relative < RADIUS_BOUND && max_radius_relative > 0.0, "{:?}", stacked.report.strategy);
}

/// An out-of-range extended texel is an error naming the parameter and its range; with clamp it is clamped and
/// counted, and the clamped value is what is evaluated.
#[test]
fn out_of_range_extended_values_are_named_or_clamped() {
    let planes = || [Plane::Constant(0.1), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)];
    let mut oxygen = vec![0.8f32; 6];
    oxygen[4] = 1.5;
    oxygen[5] = f32::NAN;
    let bad = || {
        with_extended(
            ParamImage::new(3, 2, planes()),
            [Plane::Constant(0.25), Plane::Constant(1.0), Plane::Texels(oxygen.clone())],
        )
    };
    let err = check_planes(&mut bad(), false).unwrap_err().to_string();
    assert!(err.contains("blood_oxygenation") && err.contains("1 NaN") && err.contains("1 out-of-range"), "{err}");
    assert!(err.contains("(1, 1)") && err.contains("(2, 1)"), "{err}");
    let mut img = bad();
    let report = check_planes(&mut img, true).unwrap();
    assert_eq!(report.len(), 1);
    assert_eq!((report[0].parameter.as_str(), report[0].nan, report[0].out_of_range), ("blood_oxygenation", 1, 1));
    let Plane::Texels(v) = &img.extended[2] else { panic!() };
    assert_eq!((v[4], v[5]), (1.0, 0.0));
    // A constant out of range too (a flag's value).
    let mut img = with_extended(ParamImage::new(3, 2, planes()), constant([0.6, 1.0, 0.75]));
    let err = check_planes(&mut img, false).unwrap_err().to_string();
    assert!(err.contains("epidermis_thickness_mm") && err.contains("0.5"), "{err}");
}

/// Extra channels of a parameter EXR are read; a missing one is the value given for it, else the default; a value
/// given overrides the channel; a single-parameter file of an extended parameter is read like the four's.
#[test]
fn extended_channels_and_files_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (3, 2);
    let ramp = |a: f32, b: f32| (0..w * h).map(|i| a + (b - a) * i as f32 / 5.0).collect::<Vec<f32>>();
    let path = dir.path().join("params.exr");
    let (m, b, hb, o, thick) = (ramp(0.0, 0.5), ramp(0.0, 1.0), ramp(0.0, 0.1), ramp(0.0, 1.0), ramp(0.05, 0.3));
    let channels: Vec<(&str, &[f32])> = vec![
        ("melanin", &m),
        ("melanin_blend", &b),
        ("hemoglobin", &hb),
        ("oiliness", &o),
        ("epidermis_thickness_mm", &thick),
    ];
    write_channels_exr(&path, w, h, &channels, ExrOptions::FLOAT_PIZ).unwrap();
    let multi = ParamInputs::Multi { path: path.clone(), constants: [None; 4] };
    let img = read_params(&multi).unwrap();
    assert_eq!(img.extended[0], Plane::Texels(thick.clone()));
    assert_eq!(img.extended[1], Plane::Constant(1.0));
    assert_eq!(img.extended[2], Plane::Constant(0.75));
    // Values for the extended ones: a constant replaces the channel and fills a missing one.
    let inputs = ParamInputs::Extended {
        inputs: Box::new(multi.clone()),
        extended: [Some(ParamSource::Constant(0.1)), None, Some(ParamSource::Constant(0.9))],
    };
    let img = read_params(&inputs).unwrap();
    assert_eq!(img.extended, [Plane::Constant(0.1), Plane::Constant(1.0), Plane::Constant(0.9)]);
    // An 8-bit PNG of the blood oxygenation maps 0..255 onto 0..1; with separate sources too.
    let png = dir.path().join("oxygen.png");
    image::GrayImage::from_raw(w as u32, h as u32, vec![0, 51, 102, 153, 204, 255]).unwrap().save(&png).unwrap();
    let inputs =
        ParamInputs::Extended { inputs: Box::new(multi), extended: [None, None, Some(ParamSource::File(png.clone()))] };
    let img = read_params(&inputs).unwrap();
    assert_eq!(img.extended[0], Plane::Texels(thick));
    assert_eq!(img.extended[2], Plane::Texels(vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]));
    let separate = ParamInputs::Extended {
        inputs: Box::new(ParamInputs::Separate([0.1, 0.5, 0.02, 0.3].map(ParamSource::Constant))),
        extended: [None, None, Some(ParamSource::File(png))],
    };
    let img = read_params(&separate).unwrap();
    assert_eq!((img.width, img.height), (w, h));
    assert_eq!(img.extended[0], Plane::Constant(0.25));
    assert_eq!(img.extended[2], Plane::Texels(vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]));
    // A file of another size is named.
    let small = dir.path().join("small.exr");
    write_channels_exr(&small, 2, 2, &[("Y", &[0.1f32; 4][..])], ExrOptions::FLOAT_PIZ).unwrap();
    let inputs = ParamInputs::Extended {
        inputs: Box::new(ParamInputs::Multi { path, constants: [None; 4] }),
        extended: [Some(ParamSource::File(small)), None, None],
    };
    let err = read_params(&inputs).unwrap_err().to_string();
    assert!(err.contains("epidermis_thickness_mm") && err.contains("2x2") && err.contains("3x2"), "{err}");
}

/// The sidecar records the extended sources and the constant values used.
#[test]
fn sidecar_records_the_extended_values() {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("face.exr");
    spectral_skin::maps::example::write_face_params(&params, 8).unwrap();
    let inputs = ParamInputs::Extended {
        inputs: Box::new(ParamInputs::Multi { path: params, constants: [None; 4] }),
        extended: [None, Some(ParamSource::Constant(2.0)), None],
    };
    let out = dir.path().join("out");
    run_maps(&inputs, &out, &MapSettings::default(), ExrOptions::default(), None).unwrap();
    let sidecar: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join(SIDECAR_FILE)).unwrap()).unwrap();
    assert_eq!(sidecar["inputs"]["extended"]["baseline_absorption_scale"]["constant"], 2.0);
    assert_eq!(sidecar["inputs"]["extended"]["blood_oxygenation"], "channel or default");
    let values = &sidecar["report"]["constant_values"];
    assert_eq!(values["baseline_absorption_scale"], 2.0);
    assert_eq!(values["epidermis_thickness_mm"], 0.25);
    assert_eq!(values["blood_oxygenation"], 0.75);
}

/// The shader table bakes the extended constants: its metadata records them and its lookups match direct evaluation
/// at those values.
#[test]
fn shader_table_bakes_the_extended_constants() {
    let prepared = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let resolution = TableResolution { melanin: 9, melanin_blend: 3, hemoglobin: 5 };
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let extended = [0.08, 1.5, 0.9];
    let table = ShaderTable::load_or_build_cancellable(
        &prepared,
        SubsurfaceMethod::Burley,
        resolution,
        extended,
        None,
        &cancel,
    )
    .unwrap();
    assert_eq!(table.meta().extended_values(), extended);
    assert_eq!(table.meta().extended["epidermis_thickness_mm"], 0.08);
    // At a node (melanin node 1 of 9 on the cube-root axis, blend node 1 of 3, haemoglobin node 2 of 5) the lookup is
    // the node's value: evaluate's at the baked extended values (to f32 rounding of the coordinates).
    let p = SkinParams::from_values([0.5 / 512.0, 0.5, 0.1 / 8.0, 0.3, 0.08, 1.5, 0.9]).unwrap();
    let (c, rad) = expected(&p);
    let (got_c, got_rad) = table.sample(p.melanin as f32, p.melanin_blend as f32, p.hemoglobin as f32);
    for k in 0..3 {
        assert!(((got_c[k] - c[k]) / c[k]).abs() < 1e-4, "{got_c:?} vs {c:?}");
        assert!(((got_rad[k] - rad[k]) / rad[k]).abs() < 1e-4, "{got_rad:?} vs {rad:?}");
    }
    let paper = expected(&SkinParams::new(p.melanin, 0.5, p.hemoglobin, 0.3).unwrap()).0;
    assert!(((paper[0] - c[0]) / c[0]).abs() > 0.01, "{paper:?} vs {c:?}");
    assert_eq!(measure_shader_error(&table, &prepared, 4).unwrap().samples, 4);
    // Metadata of a table written before the extended physiology existed reads as the defaults.
    let mut json = serde_json::to_value(table.meta()).unwrap();
    json.as_object_mut().unwrap().remove("extended");
    let old: spectral_skin::maps::shader_table::ShaderTableMeta = serde_json::from_value(json).unwrap();
    assert_eq!(old.extended_values(), EXTENDED_DEFAULTS);
}
