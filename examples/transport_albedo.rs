//! The table of albedo per preset before and after issue 20 (docs/model.md, "What changes for artists"): the paper's
//! diffusion totals against the exact adding-doubling ones, at the default accuracy and target (linear Rec.709, D65,
//! CIE 1931 2°).
//!
//! `cargo run --release --example transport_albedo` writes the markdown table into docs/model.md's block
//! `transport albedo`, stamped with the model's version, and prints it.

use std::fmt::Write;
use std::path::Path;

use spectral_skin::transport::Transport;
use spectral_skin::{evaluate, Outputs, Request, PRESETS};

const DOC: &str = "docs/model.md";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let albedo = |params, transport| -> Result<[f64; 3], spectral_skin::SkinError> {
        let request = Request { transport, ..Request::new(Outputs { albedo: true, ..Outputs::default() }) };
        Ok(evaluate(params, &request)?.diffuse_reflectance_rgb.unwrap_or_default())
    };
    let mut table = String::from("| preset | diffusion (the paper's) | adding_doubling (default) | change R, G, B |\n");
    table.push_str("|---|---|---|---|\n");
    for preset in PRESETS {
        let before = albedo(&preset.params, Transport::Diffusion)?;
        let after = albedo(&preset.params, Transport::AddingDoubling)?;
        let rgb = |v: [f64; 3]| format!("{:.3}, {:.3}, {:.3}", v[0], v[1], v[2]);
        let change: Vec<String> = (0..3).map(|c| format!("{:+.1} %", 100.0 * (after[c] / before[c] - 1.0))).collect();
        writeln!(table, "| {} | {} | {} | {} |", preset.name, rgb(before), rgb(after), change.join(", "))?;
    }
    let command = "cargo run --release --example transport_albedo";
    spectral_skin::stamp::write_markdown_blocks(Path::new(DOC), command, &[("transport albedo", &table)])?;
    print!("{table}");
    Ok(())
}
