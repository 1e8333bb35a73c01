//! The map pipeline's output choice (`MapSettings::request.outputs`): a map run computes only the maps asked for,
//! its work counts say so, and the maps it keeps are those of a full run (without the radius, Base Color is the
//! albedo, checked against `evaluate(outputs = albedo)`).

use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::example::face_params;
use spectral_skin::maps::io::{default_extended, ExrOptions, ParamImage, ParamInputs, ParamSource, Plane};
use spectral_skin::maps::lut::TableResolution;
use spectral_skin::maps::pipeline::{MapResult, SpecularOutput, Strategy, ALBEDO_FILE, RADIUS_FILE, SIDECAR_FILE};
use spectral_skin::maps::{compute_maps, run_maps, MapSettings, StrategyChoice};
use spectral_skin::{evaluate, Outputs, Request, SkinParams};

fn outputs(albedo: bool, radius: bool, specular: bool) -> Outputs {
    Outputs { albedo, radius, specular, ..Outputs::default() }
}

fn settings(method: SubsurfaceMethod, strategy: StrategyChoice, wanted: Outputs) -> MapSettings {
    MapSettings {
        method,
        strategy,
        // A small table keeps the test quick; what is counted does not depend on the size.
        table: TableResolution { melanin: 5, melanin_blend: 3, hemoglobin: 4 },
        table_check_samples: 8,
        request: Request::new(wanted),
        ..MapSettings::default()
    }
}

/// The four strategies: a constant map, a mask of three tuples, every texel direct, and the table.
fn cases() -> Vec<(&'static str, ParamImage, StrategyChoice)> {
    let constant = ParamImage {
        width: 16,
        height: 8,
        planes: [Plane::Constant(0.1), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Constant(0.3)],
        extended: default_extended(),
        notes: Vec::new(),
    };
    let mask: Vec<f32> = (0..16 * 8).map(|i| [0.01, 0.2, 0.4][(i / 16) % 3]).collect();
    let oil: Vec<f32> = (0..16 * 8).map(|i| (i % 7) as f32 / 6.0).collect();
    let tuples = ParamImage {
        width: 16,
        height: 8,
        planes: [Plane::Texels(mask), Plane::Constant(0.5), Plane::Constant(0.02), Plane::Texels(oil)],
        extended: default_extended(),
        notes: Vec::new(),
    };
    vec![
        ("constant", constant, StrategyChoice::Auto),
        ("tuples", tuples, StrategyChoice::Auto),
        ("exact", face_params(6), StrategyChoice::Exact),
        ("table", face_params(48), StrategyChoice::Auto),
    ]
}

fn run(image: &ParamImage, method: SubsurfaceMethod, strategy: StrategyChoice, wanted: Outputs) -> MapResult {
    compute_maps(image, &settings(method, strategy, wanted), None).unwrap()
}

/// Without the radius: no radius fit anywhere (direct evaluations and table nodes alike), no radius map, and Base
/// Color is the albedo: Burley's Base Color of the full run to the bit, for any method.
#[test]
fn without_radius_no_radius_is_fitted() {
    for (name, image, strategy) in cases() {
        let n = image.width * image.height;
        let full = run(&image, SubsurfaceMethod::Burley, strategy, Outputs::material());
        let kind = match full.report.strategy {
            Strategy::Constant => "constant",
            Strategy::DistinctTuples { .. } => "tuples",
            Strategy::Exact { .. } => "exact",
            Strategy::Table { .. } => "table",
            Strategy::ThicknessTables { .. } => "thickness_tables",
            Strategy::None => "none",
        };
        assert_eq!(kind, name, "the case takes the strategy it is named for");
        let fw = full.report.work;
        assert_eq!(fw.radius_fits, 3 * (fw.evaluations + fw.table_nodes_built), "{name}: {fw:?}");
        assert!(fw.radius_fits > 0, "{name}: {fw:?}");
        assert_eq!((fw.outputs.albedo, fw.outputs.radius), (n, n), "{name}");
        for method in [SubsurfaceMethod::Burley, SubsurfaceMethod::RandomWalk, SubsurfaceMethod::RandomWalkSkin] {
            let r = run(&image, method, strategy, outputs(true, false, true));
            let w = r.report.work;
            assert_eq!(w.radius_fits, 0, "{name} {method:?}: {w:?}");
            assert_eq!((w.outputs.albedo, w.outputs.radius), (n, 0), "{name} {method:?}");
            // The same evaluations and nodes, each the albedo alone.
            assert_eq!(
                (w.evaluations, w.table_nodes_built, w.table_lookups),
                (fw.evaluations, fw.table_nodes_built, fw.table_lookups),
                "{name} {method:?}"
            );
            assert!(
                r.radius_mm.is_none(),
                "{name} {method:?}: a radius of {:?} texels",
                r.radius_mm.as_ref().map(|p| p[0].len())
            );
            assert_eq!(r.base_color, full.base_color, "{name} {method:?}: Base Color is Burley's, the albedo");
        }
    }
}

/// Base Color without the radius is `evaluate`'s albedo, texel by texel (exact mode, a method whose full Base Color
/// is not the albedo).
#[test]
#[allow(clippy::needless_range_loop)] // texel i of three planes and of the image
fn base_color_without_radius_is_the_albedo() {
    let image = face_params(5);
    let r = run(&image, SubsurfaceMethod::RandomWalk, StrategyChoice::Exact, outputs(true, false, false));
    let base_color = r.base_color.unwrap();
    let full = run(&image, SubsurfaceMethod::RandomWalk, StrategyChoice::Exact, Outputs::material());
    let mut differs = false;
    for i in 0..image.texel_count() {
        let v = |k: usize| image.planes[k].value(i) as f64;
        let p = SkinParams::new(v(0), v(1), v(2).min(0.1), 0.0).unwrap();
        let albedo = evaluate(&p, &Request::new(outputs(true, false, false))).unwrap().diffuse_reflectance_rgb.unwrap();
        for c in 0..3 {
            assert_eq!(base_color[c][i], albedo[c] as f32, "texel {i}");
            differs |= full.base_color.as_ref().unwrap()[c][i] != base_color[c][i];
        }
    }
    assert!(
        differs,
        "the random walk's own Base Color is not the albedo, so this test tells them apart: all {} texels equal",
        image.texel_count()
    );
}

/// Without specular: no specular input computed, no specular output; Base Color and radius as in the full run.
/// Specular alone: no material evaluated at all, the specular output as in the full run.
#[test]
fn specular_is_computed_only_when_asked() {
    for (name, image, strategy) in cases() {
        let n = image.width * image.height;
        let full = run(&image, SubsurfaceMethod::RandomWalk, strategy, Outputs::material());
        assert!(full.report.work.specular_evaluations > 0, "{name}: {:?}", full.report.work);
        let r = run(&image, SubsurfaceMethod::RandomWalk, strategy, outputs(true, true, false));
        let w = r.report.work;
        assert_eq!((w.specular_evaluations, w.outputs.specular), (0, 0), "{name}: {w:?}");
        assert!(r.specular.is_none(), "{name}: a specular output without specular asked: {:?}", r.report.work);
        assert_eq!((r.base_color, r.radius_mm), (full.base_color.clone(), full.radius_mm.clone()), "{name}");
        assert_eq!(
            (w.evaluations, w.radius_fits),
            (full.report.work.evaluations, full.report.work.radius_fits),
            "{name}"
        );

        let s = run(&image, SubsurfaceMethod::RandomWalk, strategy, outputs(false, false, true));
        let w = s.report.work;
        assert_eq!(s.report.strategy, Strategy::None, "{name}");
        assert_eq!((w.evaluations, w.table_nodes_built, w.table_lookups, w.radius_fits), (0, 0, 0, 0), "{name}");
        assert_eq!((w.outputs.albedo, w.outputs.radius), (0, 0), "{name}");
        assert_eq!(w.specular_evaluations, full.report.work.specular_evaluations, "{name}");
        assert!(
            s.base_color.is_none() && s.radius_mm.is_none(),
            "{name}: specular alone kept a Base Color of {:?} and a radius of {:?} texels",
            s.base_color.as_ref().map(|p| p[0].len()),
            s.radius_mm.as_ref().map(|p| p[0].len())
        );
        match (s.specular.unwrap(), full.specular.unwrap()) {
            (SpecularOutput::Map { specular_ior_level: a, .. }, SpecularOutput::Map { specular_ior_level: b, .. }) => {
                assert_eq!(a, b, "{name}");
                assert_eq!(w.outputs.specular, n, "{name}");
            }
            (SpecularOutput::Constant(a), SpecularOutput::Constant(b)) => assert_eq!(a, b, "{name}"),
            _ => panic!("{name}: specular changed kind"),
        }
        // The radius alone: fitted (the albedo with it), Base Color not kept.
        let r = run(&image, SubsurfaceMethod::RandomWalk, strategy, outputs(false, true, false));
        assert!(
            r.base_color.is_none(),
            "{name}: radius alone kept a Base Color of {:?} texels",
            r.base_color.as_ref().map(|p| p[0].len())
        );
        assert_eq!(r.radius_mm, full.radius_mm, "{name}");
        assert_eq!(r.report.work.outputs.albedo, 0, "{name}");
    }
}

/// The albedo-only table is cached apart from the full one: a full table in the cache is not taken for it (nor it
/// for the full one), and a second albedo-only run reads its own.
#[test]
fn albedo_only_table_is_cached_apart() {
    let dir = tempfile::tempdir().unwrap();
    let image = face_params(48);
    let with_cache = |wanted: Outputs| MapSettings {
        table_cache: Some(dir.path().to_path_buf()),
        ..settings(SubsurfaceMethod::Burley, StrategyChoice::Auto, wanted)
    };
    let from_cache = |r: &MapResult| match r.report.strategy {
        Strategy::Table { from_cache, .. } => from_cache,
        ref s => panic!("not the table: {s:?}"),
    };
    let full = compute_maps(&image, &with_cache(Outputs::material()), None).unwrap();
    let albedo = compute_maps(&image, &with_cache(outputs(true, false, false)), None).unwrap();
    assert!(
        !from_cache(&full) && !from_cache(&albedo),
        "from the cache in an empty folder: full {}, albedo only {}",
        from_cache(&full),
        from_cache(&albedo)
    );
    assert_eq!(albedo.report.work.radius_fits, 0);
    let again = compute_maps(&image, &with_cache(outputs(true, false, false)), None).unwrap();
    assert!(from_cache(&again), "second albedo-only run: {:?}", again.report.strategy);
    assert_eq!(again.base_color, albedo.base_color);
    assert!(again.radius_mm.is_none(), "a radius of {:?} texels", again.radius_mm.as_ref().map(|p| p[0].len()));
    let full_again = compute_maps(&image, &with_cache(Outputs::material()), None).unwrap();
    assert!(from_cache(&full_again), "second full run: {:?}", full_again.report.strategy);
    assert_eq!(full_again.radius_mm, full.radius_mm);
}

/// `run_maps` writes only the maps asked for, and the sidecar lists only those.
#[test]
fn run_maps_writes_only_what_was_asked() {
    let dir = tempfile::tempdir().unwrap();
    let sources = [0.1, 0.5, 0.02, 0.3].map(ParamSource::Constant);
    let mut separate = sources.clone();
    let texels = dir.path().join("melanin.exr");
    spectral_skin::maps::io::write_channels_exr(&texels, 4, 2, &[("Y", &[0.1f32; 8])], ExrOptions::default()).unwrap();
    separate[0] = ParamSource::File(texels);
    let out = dir.path().join("maps");
    let wanted = settings(SubsurfaceMethod::Burley, StrategyChoice::Auto, outputs(true, false, false));
    let report = run_maps(&ParamInputs::Separate(separate), &out, &wanted, ExrOptions::default(), None).unwrap();
    assert_eq!((report.work.radius_fits, report.work.specular_evaluations), (0, 0));
    let written = || std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name()).collect::<Vec<_>>();
    assert!(out.join(ALBEDO_FILE).is_file() && out.join(SIDECAR_FILE).is_file(), "{:?}", written());
    assert!(!out.join(RADIUS_FILE).exists(), "{:?}", written());
    let sidecar: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join(SIDECAR_FILE)).unwrap()).unwrap();
    let listed: Vec<&String> = sidecar["outputs"].as_object().unwrap().keys().collect();
    assert_eq!(listed, [ALBEDO_FILE]);
    assert_eq!(sidecar["report"]["request"]["outputs"]["radius"], false);
}
