//! Measured skin colours: the Xiao et al. 2016 in-vivo reflectance spectra (data/xiao2016_skin_reflectance_400_700nm
//! .csv, 400-700 nm every 10 nm) as linear RGB under D65 with the CIE 1931 observer, by the core's colour integration
//! (the reflectance is held flat outside 400-700 nm, where the data stop).

use spectral_skin::color::{spectral_rgb_weights, spectrum_to_rgb, WavelengthGrid, WorkingSpace};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/xiao2016_skin_reflectance_400_700nm.csv");

/// Every `every`th spectrum of the data file and its wavelengths (from the header `index,R400,...`).
pub fn xiao_spectra(every: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(DATA).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let wl = lines.next().unwrap().split(',').skip(1).map(|h| h[1..].parse().unwrap()).collect();
    let spectra = lines.step_by(every).map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect()).collect();
    (wl, spectra)
}

/// `count` measured skin colours spread evenly over the data file (its eight ethnic groups), linear RGB in `space`.
pub fn measured_skin_colours(count: usize, space: WorkingSpace) -> Vec<[f64; 3]> {
    let (wl, all) = xiao_spectra(1);
    let weights = spectral_rgb_weights(&WavelengthGrid { wavelengths_nm: wl }, space);
    let every = all.len() / count;
    all.iter().step_by(every).take(count).map(|s| spectrum_to_rgb(s, &weights)).collect()
}

/// A photograph of measured skin, simulated: the Xiao spectra (`count`, spread as in [`measured_skin_colours`]) lit
/// by CIE illuminant A (a tungsten lamp: Planck's law at 2856 K with c2 = 1.435e-2 m K, CIE 15:2004) and taken by a
/// camera left at daylight white balance (XYZ to linear Rec.709 for the D65 white, the lamp's white at Y = 1), times
/// `exposure` and a shading that varies from 0.6 to 1.1 over the texels, then stored as 8-bit sRGB (clipped at 1) and
/// decoded: what a texture made from a photograph holds instead of an albedo.
pub fn tungsten_photograph(count: usize, exposure: f64) -> Vec<[f64; 3]> {
    use spectral_skin::color::cmf::cie1931_2deg;
    let (wl, all) = xiao_spectra(1);
    let every = all.len() / count;
    let planck = |nm: f64| nm.powi(-5) / ((1.435e7 / (nm * 2856.0)).exp() - 1.0);
    let cmf = cie1931_2deg();
    let reflectance = |s: &[f64], nm: f64| -> f64 {
        let k = wl.partition_point(|&w| w <= nm).clamp(1, wl.len() - 1);
        let t = ((nm - wl[k - 1]) / (wl[k] - wl[k - 1])).clamp(0.0, 1.0);
        s[k - 1] + t * (s[k] - s[k - 1])
    };
    let xyz_of = |s: &dyn Fn(f64) -> f64| -> [f64; 3] {
        let mut xyz = [0.0; 3];
        for nm in 380..=780 {
            let nm = nm as f64;
            for (c, v) in xyz.iter_mut().enumerate() {
                *v += s(nm) * planck(nm) * cmf.interpolate(c, nm);
            }
        }
        xyz
    };
    let white = xyz_of(&|_| 1.0);
    let d65 = spectral_skin::color::spectrum_to_xyz(
        &[1.0; 401],
        &WavelengthGrid { wavelengths_nm: (380..=780).map(f64::from).collect() }.xyz_weights(),
    );
    let m = WorkingSpace::LinearRec709.xyz_to_rgb_matrix(d65);
    let srgb_8bit = |v: f64| -> f64 {
        let v = v.clamp(0.0, 1.0);
        let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
        let e = (e * 255.0).round() / 255.0;
        if e <= 0.04045 {
            e / 12.92
        } else {
            ((e + 0.055) / 1.055).powf(2.4)
        }
    };
    all.iter()
        .step_by(every)
        .take(count)
        .enumerate()
        .map(|(i, s)| {
            let xyz = xyz_of(&|nm| reflectance(s, nm)).map(|v| v / white[1]);
            let shade = exposure * (0.6 + 0.25 * (1.0 + (i as f64 * 0.37).sin()));
            spectral_skin::color::rgb::mat_vec(m, xyz).map(|v| srgb_8bit(v * shade))
        })
        .collect()
}

/// The linear Rec.709 of a white reflector in [`tungsten_photograph`] at exposure 1 and no shading.
pub fn tungsten_white() -> [f64; 3] {
    use spectral_skin::color::cmf::cie1931_2deg;
    let planck = |nm: f64| nm.powi(-5) / ((1.435e7 / (nm * 2856.0)).exp() - 1.0);
    let cmf = cie1931_2deg();
    let mut xyz = [0.0; 3];
    for nm in 380..=780 {
        let nm = nm as f64;
        for (c, v) in xyz.iter_mut().enumerate() {
            *v += planck(nm) * cmf.interpolate(c, nm);
        }
    }
    let y = xyz[1];
    let d65 = spectral_skin::color::spectrum_to_xyz(
        &[1.0; 401],
        &WavelengthGrid { wavelengths_nm: (380..=780).map(f64::from).collect() }.xyz_weights(),
    );
    spectral_skin::color::rgb::mat_vec(WorkingSpace::LinearRec709.xyz_to_rgb_matrix(d65), xyz.map(|v| v / y))
}
