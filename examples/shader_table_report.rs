//! The shader table's error/size/time front: docs/shader-table.md.
//!
//! For each resolution and for Christensen-Burley and Random Walk (Cycles, the newest Blender): the build time of
//! the table (all threads), the size of its two images (float32 texels, and the EXR files as written), the worst
//! relative error of the node group's lookup (`ShaderTable::sample`, which emulates it) against direct evaluation
//! at 2000 points (cell centres and a low-discrepancy sequence) per output, and, as a check of the layout, the
//! largest difference between that lookup and the material table's own trilinear lookup at the same points.
//!
//!     cargo run --release --example shader_table_report [-- OUT.md]     (default docs/shader-table.md; ~2 min)

use std::fmt::Write as _;
use std::time::Instant;

use spectral_skin::evaluate::Prepared;
use spectral_skin::fit::SubsurfaceMethod;
use spectral_skin::maps::lut::{check_point_params, check_points, MaterialTable, TableResolution};
use spectral_skin::maps::shader_table::{
    measure_shader_error, ShaderTable, DEFAULT_SHADER_TABLE_RESOLUTION, SHADER_TABLE_EXR,
};
use spectral_skin::{Outputs, Request};

const SAMPLES: usize = 2000;

const RESOLUTIONS: [(usize, usize, usize); 9] =
    [(9, 3, 5), (17, 5, 9), (25, 5, 13), (33, 5, 17), (33, 7, 17), (33, 9, 17), (49, 9, 25), (65, 9, 33), (65, 13, 33)];

struct Row {
    resolution: TableResolution,
    build_s: f64,
    texel_kib: f64,
    exr_kib: f64,
    base_color: f64,
    radius: f64,
    vs_table: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "docs/shader-table.md".to_string());
    let request = Request::new(Outputs::material());
    let prepared = Prepared::new(&request)?;
    let target = request.target.info();
    let mut md = String::new();
    writeln!(md, "{}", spectral_skin::stamp::markdown_stamp("cargo run --release --example shader_table_report"))?;
    writeln!(md)?;
    writeln!(md, "# Shader table: error, size and build time")?;
    writeln!(md)?;
    md.push_str(include_str!("shader_table_report.md"));
    writeln!(md)?;
    writeln!(
        md,
        "Target: Blender {} {}; {} points per row; {} threads.",
        target.blender,
        target.engine.name(),
        SAMPLES,
        rayon::current_num_threads()
    )?;
    for method in [SubsurfaceMethod::Burley, SubsurfaceMethod::RandomWalk] {
        let mut rows = Vec::new();
        for (m, b, h) in RESOLUTIONS {
            let resolution = TableResolution { melanin: m, melanin_blend: b, hemoglobin: h };
            let start = Instant::now();
            let table = MaterialTable::build(&prepared, method, resolution)?;
            let shader = ShaderTable::from_table(&table, &prepared)?;
            let build_s = start.elapsed().as_secs_f64();
            let dir = tempfile::tempdir()?;
            let paths = shader.write(dir.path(), None, SHADER_TABLE_EXR)?;
            let exr_bytes: u64 = paths[..2].iter().map(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0)).sum();
            let error = measure_shader_error(&shader, &prepared, SAMPLES)?;
            let mut vs_table = 0.0f64;
            for u in check_points(resolution, SAMPLES) {
                let p = check_point_params(u);
                let (c_m, beta, c_h) = (p.melanin as f32, p.melanin_blend as f32, p.hemoglobin as f32);
                let (bc, rad) = shader.sample(c_m, beta, c_h);
                let (bc_t, rad_t) = table.lookup_method(c_m, beta, c_h);
                for c in 0..3 {
                    vs_table = vs_table.max(((bc[c] - bc_t[c]) / bc_t[c]).abs() as f64);
                    vs_table = vs_table.max(((rad[c] - rad_t[c]) / rad_t[c]).abs() as f64);
                }
            }
            eprintln!("{} {m}x{b}x{h}: {build_s:.2} s, {error:?}", method.name());
            rows.push(Row {
                resolution,
                build_s,
                texel_kib: shader.texel_bytes() as f64 / 1024.0,
                exr_kib: exr_bytes as f64 / 1024.0,
                base_color: error.max_base_color_relative,
                radius: error.max_radius_relative,
                vs_table,
            });
        }
        writeln!(md)?;
        writeln!(md, "## {}", method.name())?;
        writeln!(md)?;
        writeln!(
            md,
            "| nodes (C_m × β_m × C_h) | image (W × H) | Base Color err (max rel.) | radius err (max rel.) | \
             texels (KiB) | EXR files (KiB) | build | shader vs table | front |"
        )?;
        writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|:---:|")?;
        for r in &rows {
            let worst = r.base_color.max(r.radius);
            // On the front: no other row is at least as good in error, texel size and build time, and better in one.
            let dominated = rows.iter().any(|o| {
                let ow = o.base_color.max(o.radius);
                ow <= worst
                    && o.texel_kib <= r.texel_kib
                    && o.build_s <= r.build_s
                    && (ow < worst || o.texel_kib < r.texel_kib || o.build_s < r.build_s)
            });
            let n = r.resolution;
            let name = format!("{}×{}×{}", n.melanin, n.melanin_blend, n.hemoglobin);
            let name = if n == DEFAULT_SHADER_TABLE_RESOLUTION { format!("**{name} (default)**") } else { name };
            writeln!(
                md,
                "| {name} | {} × {} | {:.3} % | {:.3} % | {:.1} | {:.1} | {:.2} s | {:.1e} | {} |",
                n.melanin_blend * (n.melanin + 2),
                n.hemoglobin,
                100.0 * r.base_color,
                100.0 * r.radius,
                r.texel_kib,
                r.exr_kib,
                r.build_s,
                r.vs_table,
                if dominated { "" } else { "★" }
            )?;
        }
    }
    std::fs::write(&out, md)?;
    eprintln!("wrote {out}");
    Ok(())
}
