//! `spectral-skin`: evaluate the Donner & Jensen 2006 skin model from the command line.

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use spectral_skin::diffusion::{Combination, MultipoleTerms};
use spectral_skin::evaluate::ProfileGrid;
use spectral_skin::{evaluate, Evaluation, Outputs, Request, SkinError, SkinParams, PRESETS};

#[derive(Parser)]
#[command(name = "spectral-skin", version, about = "Spectral skin BSSRDF (Donner & Jensen 2006) for Blender's Principled BSDF")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Albedo, Subsurface Radius per Cycles method and specular inputs for one set of parameters.
    Eval {
        #[command(flatten)]
        skin: SkinArgs,
        #[command(flatten)]
        accuracy: AccuracyArgs,
        /// Print the stable JSON interface instead of a summary.
        #[arg(long)]
        json: bool,
    },
    /// Radial reflectance profile R(r) in mm^-2.
    Profile {
        #[command(flatten)]
        skin: SkinArgs,
        #[command(flatten)]
        accuracy: AccuracyArgs,
        /// One column per wavelength instead of R, G, B.
        #[arg(long)]
        spectral: bool,
        /// Print CSV (the only format for now; accepted for explicitness).
        #[arg(long)]
        csv: bool,
        /// Smallest radius, mm.
        #[arg(long, default_value_t = ProfileGrid::default().r_min_mm)]
        r_min_mm: f64,
        /// Largest radius, mm.
        #[arg(long, default_value_t = ProfileGrid::default().r_max_mm)]
        r_max_mm: f64,
        /// Number of log-spaced radii.
        #[arg(long, default_value_t = ProfileGrid::default().count)]
        count: usize,
    },
    /// List the named presets.
    Presets,
}

#[derive(Args)]
struct SkinArgs {
    /// Named preset (caucasian, asian, african); explicit parameters override its values.
    #[arg(long)]
    preset: Option<String>,
    /// Melanin fraction C_m of the epidermis, 0..0.5.
    #[arg(long)]
    melanin: Option<f64>,
    /// Eumelanin share beta_m of the melanin, 0..1.
    #[arg(long)]
    melanin_blend: Option<f64>,
    /// Blood fraction C_h of the dermis, 0..0.1.
    #[arg(long)]
    hemoglobin: Option<f64>,
    /// Oiliness rho_s of the surface, 0..1.
    #[arg(long)]
    oiliness: Option<f64>,
}

#[derive(Args)]
struct AccuracyArgs {
    /// Wavelength step, nm (380-780 nm).
    #[arg(long, default_value_t = 5.0)]
    wavelength_step_nm: f64,
    /// Image-source pairs of the multipole (default: the whole series in closed form).
    #[arg(long)]
    multipole_pairs: Option<u32>,
    /// Layer combination.
    #[arg(long, value_enum, default_value_t = CombinationArg::Directional)]
    combination: CombinationArg,
}

#[derive(Clone, Copy, ValueEnum)]
enum CombinationArg {
    Directional,
    Symmetric,
}

impl SkinArgs {
    fn params(&self) -> Result<SkinParams, SkinError> {
        let base = match &self.preset {
            Some(name) => Some(SkinParams::preset(name)?),
            None => None,
        };
        let pick = |explicit: Option<f64>, from_preset: Option<f64>, flag: &str| {
            explicit.or(from_preset).ok_or_else(|| {
                SkinError::Invalid { name: flag.to_string(), reason: format!("give --preset or --{flag}") }
            })
        };
        SkinParams::new(
            pick(self.melanin, base.map(|p| p.melanin), "melanin")?,
            pick(self.melanin_blend, base.map(|p| p.melanin_blend), "melanin-blend")?,
            pick(self.hemoglobin, base.map(|p| p.hemoglobin), "hemoglobin")?,
            pick(self.oiliness, base.map(|p| p.oiliness), "oiliness")?,
        )
    }
}

impl AccuracyArgs {
    fn request(&self, outputs: Outputs) -> Request {
        let mut r = Request::new(outputs);
        r.accuracy.wavelength_step_nm = self.wavelength_step_nm;
        if let Some(n) = self.multipole_pairs {
            r.accuracy.multipole_terms = MultipoleTerms::Pairs(n);
        }
        r.combination = match self.combination {
            CombinationArg::Directional => Combination::Directional,
            CombinationArg::Symmetric => Combination::Symmetric,
        };
        r
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Eval { skin, accuracy, json } => {
            let params = skin.params()?;
            let ev = evaluate(&params, &accuracy.request(Outputs::material()))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&ev)?);
            } else {
                print_summary(&ev);
            }
        }
        Command::Profile { skin, accuracy, spectral, csv: _, r_min_mm, r_max_mm, count } => {
            let params = skin.params()?;
            let outputs = Outputs { profile_rgb: !spectral, profile_spectral: spectral, ..Outputs::default() };
            let mut request = accuracy.request(outputs);
            request.accuracy.profile_grid = ProfileGrid { r_min_mm, r_max_mm, count };
            let ev = evaluate(&params, &request)?;
            print_profile_csv(&ev);
        }
        Command::Presets => {
            for p in PRESETS {
                let q = p.params;
                println!(
                    "{:<10} melanin {:<5} melanin_blend {:<4} hemoglobin {:<5} oiliness {:<4} ({})",
                    p.name, q.melanin, q.melanin_blend, q.hemoglobin, q.oiliness, p.description
                );
            }
        }
    }
    Ok(())
}

fn print_summary(ev: &Evaluation) {
    let p = ev.params;
    println!(
        "parameters: melanin {} melanin_blend {} hemoglobin {} oiliness {}",
        p.melanin, p.melanin_blend, p.hemoglobin, p.oiliness
    );
    println!("colour space: {}", ev.color_space);
    if let Some(a) = ev.diffuse_reflectance_rgb {
        println!("diffuse reflectance (RGB): {:.4} {:.4} {:.4}", a[0], a[1], a[2]);
    }
    if let Some(m) = ev.methods {
        for (name, mp) in [("burley", m.burley), ("random_walk", m.random_walk)] {
            let tag = if name == ev.default_method { " (default)" } else { "" };
            println!(
                "{name}{tag}: base color {:.4} {:.4} {:.4}, subsurface radius {:.4} {:.4} {:.4} mm",
                mp.base_color[0],
                mp.base_color[1],
                mp.base_color[2],
                mp.subsurface_radius_mm[0],
                mp.subsurface_radius_mm[1],
                mp.subsurface_radius_mm[2]
            );
        }
    }
    if let Some(s) = &ev.specular {
        println!("specular: IOR level {:.4}, roughness {:.4}, IOR {}", s.specular_ior_level, s.roughness, s.ior);
    }
    println!("computed in {:.1} ms", 1e3 * ev.seconds);
}

fn print_profile_csv(ev: &Evaluation) {
    let Some(profile) = &ev.profile else { return };
    if let Some(rgb) = &profile.rgb_per_mm2 {
        println!("r_mm,r_per_mm2,g_per_mm2,b_per_mm2");
        for (r, v) in profile.radii_mm.iter().zip(rgb) {
            println!("{r:.6e},{:.6e},{:.6e},{:.6e}", v[0], v[1], v[2]);
        }
    }
    if let (Some(spectral), Some(wavelengths)) = (&profile.spectral_per_mm2, &ev.wavelengths_nm) {
        let header: Vec<String> = wavelengths.iter().map(|w| format!("nm{w}_per_mm2")).collect();
        println!("r_mm,{}", header.join(","));
        for (i, r) in profile.radii_mm.iter().enumerate() {
            let row: Vec<String> = spectral.iter().map(|p| format!("{:.6e}", p[i])).collect();
            println!("{r:.6e},{}", row.join(","));
        }
    }
}
