//! The map pipeline: strategies, table accuracy against direct evaluation, exactness against `evaluate`, bad input,
//! and that failures leave no output behind.

use std::path::Path;

use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::blender_target::Target;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::example::{face_params, write_face_params};
use spectral_skin::maps::io::{
    read_exr_channels, write_channels_exr, ExrOptions, ParamImage, ParamInputs, ParamSource, Plane, Precision,
};
use spectral_skin::maps::lut::{measure_error, MaterialTable, TableResolution};
use spectral_skin::maps::pipeline::{
    check_planes, Strategy, ALBEDO_FILE, COAT_ROUGHNESS_MAP, COAT_WEIGHT_MAP, RADIUS_FILE, SIDECAR_FILE, SPECULAR_FILE,
};
use spectral_skin::maps::{compute_maps, run_maps, MapSettings, StrategyChoice};
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

fn image(width: usize, height: usize, planes: [Plane; 4]) -> ParamImage {
    ParamImage::new(width, height, planes)
}

/// The default table's worst error over the whole domain (2000 points: cell centres and a low-discrepancy sequence,
/// each evaluated directly) is below 0.5 % in albedo and Base Color and 1 % in radius, for every kind of target
/// mapping: Cycles Burley, the random walk up to 5.1 and from 5.2 (Van de Hulst, radius without 4 pi), and EEVEE
/// (radius compensated per node from that node's albedo, then interpolated).
#[test]
fn table_error_is_within_bounds() {
    for (blender, engine, method) in [
        ("5.3", "cycles", SubsurfaceMethod::Burley),
        ("5.0", "cycles", SubsurfaceMethod::RandomWalk),
        ("5.3", "cycles", SubsurfaceMethod::RandomWalk),
        ("5.3", "eevee", SubsurfaceMethod::Burley),
    ] {
        let target = Target::parse(blender, engine).unwrap();
        let prepared = Prepared::new(&Request { target, ..Request::new(Outputs::material()) }).unwrap();
        let table = MaterialTable::build(&prepared, method, TableResolution::default()).unwrap();
        let err = measure_error(&table, &prepared, 2000).unwrap();
        println!("table {:?} {blender} {engine} {}: {err:?}", TableResolution::default(), method.name());
        assert!(err.max_albedo_relative < 0.005, "{blender} {engine} {method:?}: {err:?}");
        assert!(err.max_radius_relative < 0.01, "{blender} {engine} {method:?}: {err:?}");
        assert!(err.max_base_color_relative < 0.005, "{blender} {engine} {method:?}: {err:?}");
    }
}

/// Every texel in exact mode is what `evaluate` gives for its parameters, for each method and kind of target.
#[test]
fn exact_mode_equals_evaluate() {
    let values = [0.0f32, 0.013, 0.27, 0.5];
    let (w, h) = (4, 3);
    let m: Vec<f32> = (0..w * h).map(|i| values[i % 4]).collect();
    let b: Vec<f32> = (0..w * h).map(|i| (i as f32 / 11.0).min(1.0)).collect();
    let hb: Vec<f32> = (0..w * h).map(|i| 0.1 * ((i * 7) % 12) as f32 / 11.0).collect();
    let img = image(
        w,
        h,
        [Plane::Texels(m.clone()), Plane::Texels(b.clone()), Plane::Texels(hb.clone()), Plane::Constant(0.3)],
    );
    for (target, method) in [
        (Target::default(), SubsurfaceMethod::Burley),
        (Target::default(), SubsurfaceMethod::RandomWalk),
        (Target::parse("4.5", "cycles").unwrap(), SubsurfaceMethod::RandomWalk),
        (Target::parse("5.3", "eevee").unwrap(), SubsurfaceMethod::Burley),
    ] {
        let request = Request { target, ..Request::new(Outputs::material()) };
        let settings = MapSettings { method, strategy: StrategyChoice::Exact, request, ..MapSettings::default() };
        let result = compute_maps(&img, &settings, None).unwrap();
        assert!(
            matches!(result.report.strategy, Strategy::Exact { .. }),
            "{target:?} {method:?}: {:?}",
            result.report.strategy
        );
        for i in 0..w * h {
            // The pipeline widens f32 texels and rounds them into range (0.1f32 is just above 0.1).
            let p = SkinParams::new(m[i] as f64, b[i] as f64, (hb[i] as f64).min(0.1), 0.3).unwrap();
            let ev = evaluate(&p, &request).unwrap();
            let expected = *ev.methods.unwrap().get(method).unwrap();
            for c in 0..3 {
                let (base_color, radius_mm) = (result.base_color.as_ref().unwrap(), result.radius_mm.as_ref().unwrap());
                assert_eq!(base_color[c][i], expected.base_color[c] as f32, "{method:?} texel {i}");
                assert_eq!(radius_mm[c][i], expected.subsurface_radius_mm[c] as f32, "{method:?} texel {i}");
            }
        }
    }
}

#[test]
fn strategies_follow_the_input() {
    let settings = MapSettings::default();
    // Constant: one evaluation.
    let constant =
        image(64, 64, [Plane::Constant(0.1), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.0)]);
    let r = compute_maps(&constant, &settings, None).unwrap();
    assert_eq!(r.report.strategy, Strategy::Constant);
    let w = r.report.work;
    // One material (three channel fits) and one specular set for 4096 texels of each output; no table, no map of
    // the specular level.
    assert_eq!((w.texels, w.evaluations, w.radius_fits, w.specular_evaluations), (4096, 1, 3, 1), "{w:?}");
    assert_eq!((w.table_nodes_built, w.table_lookups), (0, 0));
    assert_eq!((w.outputs.albedo, w.outputs.radius, w.outputs.specular), (4096, 4096, 0));
    // A map whose texels all hold one value is constant too.
    let uniform = image(
        64,
        64,
        [
            Plane::Texels(vec![0.1; 4096]),
            Plane::Constant(0.5),
            Plane::Texels(vec![0.02; 4096]),
            Plane::Texels(vec![0.3; 4096]),
        ],
    );
    let r = compute_maps(&uniform, &settings, None).unwrap();
    assert_eq!(r.report.strategy, Strategy::Constant);
    assert!(matches!(r.specular, Some(spectral_skin::maps::pipeline::SpecularOutput::Constant(_))), "{:?}", r.specular);
    // A mask with three values: one evaluation per tuple.
    let mask: Vec<f32> = (0..64 * 64).map(|i| [0.01, 0.2, 0.4][(i / 64) % 3]).collect();
    let masked =
        image(64, 64, [Plane::Texels(mask), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.2)]);
    let r = compute_maps(&masked, &settings, None).unwrap();
    assert_eq!(r.report.strategy, Strategy::DistinctTuples { tuples: 3 });
    let w = r.report.work;
    assert_eq!((w.evaluations, w.radius_fits, w.table_nodes_built), (3, 9, 0), "{w:?}");
    // The oiliness is one value (0.2): one specular set, no specular map.
    assert_eq!((w.specular_evaluations, w.outputs.specular), (1, 0));
    // Smooth variation everywhere: the table.
    let face = face_params(64);
    let r = compute_maps(&face, &settings, None).unwrap();
    assert!(matches!(r.report.strategy, Strategy::Table { .. }), "{:?}", r.report.strategy);
    let w = r.report.work;
    let res = TableResolution::default();
    let nodes = res.melanin * res.melanin_blend * res.hemoglobin;
    // No cache folder: the table is built (every node a material) and checked at the default 64 points.
    assert_eq!((w.table_nodes_built, w.evaluations, w.table_lookups), (nodes, 64, 64 * 64), "{w:?}");
    assert_eq!(w.radius_fits, 3 * (nodes + 64));
    // The face's oiliness varies: one specular set per texel, and a specular map.
    assert_eq!((w.specular_evaluations, w.outputs.specular), (64 * 64, 64 * 64));
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| rd.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn writes_the_documented_files() {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("face.exr");
    write_face_params(&params, 48).unwrap();
    let out = dir.path().join("out");
    let report = run_maps(
        &ParamInputs::Multi { path: params, constants: [None; 4] },
        &out,
        &MapSettings::default(),
        ExrOptions::default(),
        None,
    )
    .unwrap();
    // The default (measured) surface with a varying oiliness: the level and the Coat's two maps.
    let (coat_weight, coat_roughness) = (COAT_WEIGHT_MAP.file, COAT_ROUGHNESS_MAP.file);
    assert_eq!(
        files_in(&out),
        vec![ALBEDO_FILE, coat_roughness, coat_weight, RADIUS_FILE, SIDECAR_FILE, SPECULAR_FILE]
    );
    for (f, expected) in [
        (ALBEDO_FILE, vec!["B", "G", "R"]),
        (RADIUS_FILE, vec!["B", "G", "R"]),
        (SPECULAR_FILE, vec!["Y"]),
        (coat_weight, vec!["Y"]),
        (coat_roughness, vec!["Y"]),
    ] {
        let (w, h, channels) = read_exr_channels(&out.join(f)).unwrap();
        assert_eq!((w, h), (48, 48), "{f}");
        let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, expected, "{f}");
        assert!(
            channels.iter().all(|(_, v)| v.iter().all(|x| x.is_finite() && *x >= 0.0)),
            "{f}: first bad (channel, texel, value): {:?}",
            channels
                .iter()
                .flat_map(|(n, v)| v.iter().enumerate().map(move |(i, x)| (n, i, *x)))
                .find(|(_, _, x)| !(x.is_finite() && *x >= 0.0))
        );
    }
    let sidecar: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join(SIDECAR_FILE)).unwrap()).unwrap();
    assert_eq!(sidecar["outputs"][RADIUS_FILE]["units"], "mm");
    assert_eq!(sidecar["report"]["strategy"]["name"], "table");
    assert!(report.seconds.total > 0.0, "{:?}", report.seconds);

    // Constant zero oiliness: no specular map, its constants in the sidecar (the measured surface reflects dry skin:
    // its level is above zero, and its Coat has the dry weight 0.15).
    let out2 = dir.path().join("out2");
    let inputs = ParamInputs::Multi { path: dir.path().join("face.exr"), constants: [None; 4] };
    let mut img = face_params(8);
    img.planes[3] = Plane::Constant(0.0);
    drop(img);
    let sep = dir.path().join("melanin.exr");
    let m: Vec<f32> = (0..64).map(|i| 0.005 * i as f32).collect();
    write_channels_exr(&sep, 8, 8, &[("Y", &m)], ExrOptions::default()).unwrap();
    let separate = ParamInputs::Separate([
        ParamSource::File(sep),
        ParamSource::Constant(0.7),
        ParamSource::Constant(0.01),
        ParamSource::Constant(0.0),
    ]);
    run_maps(
        &separate,
        &out2,
        &MapSettings::default(),
        ExrOptions { precision: Precision::Half, ..ExrOptions::default() },
        None,
    )
    .unwrap();
    assert_eq!(files_in(&out2), vec![ALBEDO_FILE, RADIUS_FILE, SIDECAR_FILE]);
    let sidecar: serde_json::Value = serde_json::from_slice(&std::fs::read(out2.join(SIDECAR_FILE)).unwrap()).unwrap();
    let constants = &sidecar["outputs"]["specular_constants"];
    assert!(constants["specular_ior_level"].as_f64().unwrap() > 0.4, "{constants}");
    assert!((constants["coat_weight"].as_f64().unwrap() - 0.15).abs() < 1e-12, "{constants}");
    let _ = inputs;
}

#[test]
fn bad_texels_are_errors_or_clamped() {
    let mut m = vec![0.1f32; 16];
    m[5] = f32::NAN;
    m[6] = f32::INFINITY;
    m[9] = 0.7;
    let planes = || [Plane::Texels(m.clone()), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)];
    let err = check_planes(&mut image(4, 4, planes()), false).unwrap_err().to_string();
    assert!(
        err.contains("melanin")
            && err.contains("1 NaN")
            && err.contains("1 infinite")
            && err.contains("1 out-of-range"),
        "{err}"
    );
    assert!(err.contains("(1, 1)") && err.contains("(2, 1)") && err.contains("(1, 2)"), "coordinates: {err}");
    let mut img = image(4, 4, planes());
    let report = check_planes(&mut img, true).unwrap();
    assert_eq!((report[0].nan, report[0].infinite, report[0].out_of_range), (1, 1, 1));
    let Plane::Texels(v) = &img.planes[0] else { panic!() };
    assert_eq!((v[5], v[6], v[9]), (0.0, 0.5, 0.5));
}

/// A failing run leaves neither new files nor clobbered old ones.
#[test]
fn failures_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join(ALBEDO_FILE), b"previous").unwrap();
    let good = dir.path().join("good.exr");
    write_face_params(&good, 16).unwrap();
    // NaN texel.
    let bad = dir.path().join("bad.exr");
    let mut m = vec![0.1f32; 16 * 16];
    m[17] = f32::NAN;
    let ones = vec![0.5f32; 16 * 16];
    let small = vec![0.01f32; 16 * 16];
    write_channels_exr(
        &bad,
        16,
        16,
        &[("melanin", &m), ("melanin_blend", &ones), ("hemoglobin", &small), ("oiliness", &ones)],
        ExrOptions::default(),
    )
    .unwrap();
    // Truncated EXR.
    let truncated = dir.path().join("truncated.exr");
    let bytes = std::fs::read(&good).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    // Mismatched sizes.
    let other = dir.path().join("other.exr");
    write_channels_exr(&other, 8, 8, &[("Y", &vec![0.5f32; 64])], ExrOptions::default()).unwrap();
    let single = dir.path().join("single.exr");
    write_channels_exr(&single, 16, 16, &[("Y", &small)], ExrOptions::default()).unwrap();
    let cases = [
        (ParamInputs::Multi { path: bad, constants: [None; 4] }, "NaN"),
        (ParamInputs::Multi { path: truncated.clone(), constants: [None; 4] }, "truncated.exr"),
        (
            ParamInputs::Separate([
                ParamSource::File(single),
                ParamSource::File(other),
                ParamSource::Constant(0.01),
                ParamSource::Constant(0.2),
            ]),
            "8x8",
        ),
        (ParamInputs::Multi { path: dir.path().join("missing.exr"), constants: [None; 4] }, "missing.exr"),
    ];
    for (inputs, needle) in cases {
        let err =
            run_maps(&inputs, &out, &MapSettings::default(), ExrOptions::default(), None).unwrap_err().to_string();
        assert!(err.contains(needle), "{needle}: {err}");
        assert_eq!(files_in(&out), vec![ALBEDO_FILE], "{needle}: outputs appeared");
        assert_eq!(std::fs::read(out.join(ALBEDO_FILE)).unwrap(), b"previous", "{needle}: clobbered");
    }
}

/// A cache file with a correct checksum but a node value no build stores (a logarithm whose exp overflows f32, or
/// NaN) is refused, so a table read back never interpolates to an infinite or NaN output; the same file with
/// values a build can store is read, and looks up exp(value). The file is assembled here from the format's
/// description (magic line, FNV-1a of the body; the body: the key's length and the key, axis sizes, nine f32 per
/// node), with FNV-1a written from its definition.
#[test]
fn cache_file_values_a_build_cannot_store_are_refused() {
    use spectral_skin::maps::lut::CACHE_MAGIC;
    let fnv1a = |bytes: &[u8]| {
        bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3))
    };
    let resolution = TableResolution { melanin: 2, melanin_blend: 2, hemoglobin: 2 };
    let key = "a request";
    let file = |value: f32| {
        let mut body: Vec<u8> = (key.len() as u32).to_le_bytes().to_vec();
        body.extend(key.as_bytes());
        body.extend([2u32, 2, 2].iter().flat_map(|n| n.to_le_bytes()));
        body.extend((0..8 * 9).flat_map(|_| value.to_le_bytes()));
        let mut file = CACHE_MAGIC.to_vec();
        file.extend(fnv1a(&body).to_le_bytes());
        file.extend(body);
        file
    };
    let read = |value: f32| MaterialTable::from_cache_bytes(&file(value), key, SubsurfaceMethod::Burley, resolution);
    let table = read(0.5f32.ln()).expect("a table of ln 0.5 everywhere");
    let t = table.lookup(0.2, 0.3, 0.05);
    assert!(t.albedo.iter().chain(&t.radius_mm).all(|v| (v - 0.5).abs() < 1e-6), "{t:?}");
    for bad in [100.0, -100.0, f32::NAN, f32::INFINITY] {
        assert!(read(bad).is_none(), "a node value of {bad} was accepted");
    }
    // The checksum still guards everything else: one flipped byte of a good file.
    let mut flipped = file(0.0);
    let last = flipped.len() - 1;
    flipped[last] ^= 1;
    assert!(
        MaterialTable::from_cache_bytes(&flipped, key, SubsurfaceMethod::Burley, resolution).is_none(),
        "a file with byte {last} of {} flipped was accepted",
        flipped.len()
    );
    // A whole, undamaged file of another request is not this request's table.
    assert!(
        MaterialTable::from_cache_bytes(&file(0.0), "another request", SubsurfaceMethod::Burley, resolution).is_none(),
        "the file of {key:?} was read for \"another request\""
    );
}

/// A valid table file of another request (another method, boundaries or extended physiology) put under a request's
/// cache name is not used: the file carries the request that built it, and a mismatch rebuilds (issue 23: such a
/// file used to give Base Colours off by up to 0.16).
#[test]
fn cache_file_of_another_request_is_rebuilt() {
    use spectral_skin::diffusion::Boundaries;
    use spectral_skin::maps::lut::cache_key;
    use spectral_skin::skin::params::EXTENDED_DEFAULTS;
    let small = TableResolution { melanin: 4, melanin_blend: 3, hemoglobin: 3 };
    let paper = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let capped =
        Prepared::new(&Request { boundaries: Boundaries::Capped, ..Request::new(Outputs::material()) }).unwrap();
    let thin = [0.05, EXTENDED_DEFAULTS[1], EXTENDED_DEFAULTS[2]];
    let cases = [
        ("another method", &paper, SubsurfaceMethod::RandomWalk, EXTENDED_DEFAULTS),
        ("other boundaries", &capped, SubsurfaceMethod::Burley, EXTENDED_DEFAULTS),
        ("another epidermis", &paper, SubsurfaceMethod::Burley, thin),
    ];
    for (what, prepared, method, extended) in cases {
        let dir = tempfile::tempdir().unwrap();
        let build = |p: &Prepared, m, e| {
            MaterialTable::load_or_build_outputs(p, m, small, true, e, Some(dir.path()), &Default::default(), None)
                .unwrap()
        };
        // The other request's table, written by the cache, renamed to the file name of the paper's Burley table.
        build(prepared, method, extended);
        let name = |p: &Prepared, m, e| dir.path().join(format!("table-{:016x}.bin", cache_key(p, m, small, true, e)));
        let ours = name(&paper, SubsurfaceMethod::Burley, EXTENDED_DEFAULTS);
        std::fs::rename(name(prepared, method, extended), &ours).unwrap();
        let (table, from_cache) = build(&paper, SubsurfaceMethod::Burley, EXTENDED_DEFAULTS);
        assert!(!from_cache, "{what}: the other request's table was read as ours");
        let fresh = MaterialTable::build(&paper, SubsurfaceMethod::Burley, small).unwrap();
        let (a, b) = (table.lookup(0.2, 0.5, 0.02), fresh.lookup(0.2, 0.5, 0.02));
        assert_eq!(a.albedo, b.albedo, "{what}: {a:?} vs {b:?}");
    }
}

/// A table kept in the cache folder is reused and equals a fresh one; a damaged cache file is rebuilt.
#[test]
fn table_cache_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let prepared = Prepared::new(&Request::new(Outputs::material())).unwrap();
    let small = TableResolution { melanin: 5, melanin_blend: 3, hemoglobin: 4 };
    let (built, cached) =
        MaterialTable::load_or_build(&prepared, SubsurfaceMethod::Burley, small, Some(dir.path())).unwrap();
    assert!(!cached, "{small:?}: the first load came from an empty cache folder {:?}", dir.path());
    let (again, cached) =
        MaterialTable::load_or_build(&prepared, SubsurfaceMethod::Burley, small, Some(dir.path())).unwrap();
    assert!(cached, "{small:?}: the second load was built afresh, cache folder {:?}", dir.path());
    for (m, b, h) in [(0.0, 0.0, 0.0), (0.13, 0.4, 0.07), (0.5, 1.0, 0.1)] {
        assert_eq!(built.lookup(m, b, h), again.lookup(m, b, h), "at ({m}, {b}, {h})");
    }
    let file = std::fs::read_dir(dir.path()).unwrap().next().unwrap().unwrap().path();
    let bytes = std::fs::read(&file).unwrap();
    std::fs::write(&file, &bytes[..bytes.len() - 7]).unwrap();
    let (_, cached) =
        MaterialTable::load_or_build(&prepared, SubsurfaceMethod::Burley, small, Some(dir.path())).unwrap();
    assert!(!cached, "a damaged cache file must be rebuilt: {file:?} cut to {} bytes", bytes.len() - 7);
}
