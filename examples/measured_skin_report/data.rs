//! The measured spectra and the statistics the measured-skin examples share (this report and examples/palette.rs,
//! which includes this file).

/// The wavelengths and spectra of the data file (comment lines start with '#'; then a header `index,R400,...`).
pub fn read_data(path: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("read the data file");
    let mut lines = spectral_skin::strip_utf8_bom(&text).lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().expect("header");
    let wavelengths: Vec<f64> = header.split(',').skip(1).map(|h| h.trim_start_matches('R').parse().unwrap()).collect();
    let spectra = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').skip(1).map(|v| v.parse().unwrap()).collect())
        .collect();
    (wavelengths, spectra)
}

/// The `q` quantile of `values`, linear between order statistics (the median at 0.5).
pub fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let pos = q * (v.len() - 1) as f64;
    let (i, t) = (pos.floor() as usize, pos.fract());
    if i + 1 < v.len() {
        v[i] * (1.0 - t) + v[i + 1] * t
    } else {
        v[i]
    }
}

/// The least spectra an ITA class needs for its median to count (towards the report's worst/best ratio, issue 39's
/// criterion) or to become a palette preset.
pub const MIN_CLASS_SPECTRA: usize = 20;
