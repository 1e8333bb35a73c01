//! The table of albedo per preset before and after issue 20 (docs/model.md, "What changes for artists"): the paper's
//! diffusion totals against the exact adding-doubling ones, at the default accuracy and target (linear Rec.709, D65,
//! CIE 1931 2°).
//!
//! `cargo run --release --example transport_albedo` prints the markdown table.

use spectral_skin::transport::Transport;
use spectral_skin::{evaluate, Outputs, Request, PRESETS};

fn main() -> Result<(), spectral_skin::SkinError> {
    let albedo = |params, transport| -> Result<[f64; 3], spectral_skin::SkinError> {
        let request = Request { transport, ..Request::new(Outputs { albedo: true, ..Outputs::default() }) };
        Ok(evaluate(params, &request)?.diffuse_reflectance_rgb.unwrap_or_default())
    };
    println!("| preset | diffusion (the paper's) | adding_doubling (default) | change R, G, B |");
    println!("|---|---|---|---|");
    for preset in PRESETS {
        let before = albedo(&preset.params, Transport::Diffusion)?;
        let after = albedo(&preset.params, Transport::AddingDoubling)?;
        let rgb = |v: [f64; 3]| format!("{:.3}, {:.3}, {:.3}", v[0], v[1], v[2]);
        let change: Vec<String> = (0..3).map(|c| format!("{:+.1} %", 100.0 * (after[c] / before[c] - 1.0))).collect();
        println!("| {} | {} | {} | {} |", preset.name, rgb(before), rgb(after), change.join(", "));
    }
    Ok(())
}
