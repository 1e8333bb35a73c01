//! Tabulated spectra shipped in `data/` (each file: one `#` provenance line, a CSV header, rows by wavelength).

/// A table of one or more columns sampled on an increasing wavelength axis (nm).
#[derive(Debug, Clone)]
pub struct SpectralTable {
    pub wavelengths_nm: Vec<f64>,
    pub columns: Vec<Vec<f64>>,
    pub names: Vec<String>,
}

/// CSV text as every CSV reader of the project takes it: a leading UTF-8 byte-order mark (U+FEFF, which spreadsheet
/// programs write at the start of a "CSV UTF-8" file) removed, the rest unchanged.
pub fn strip_utf8_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

impl SpectralTable {
    /// Parse a bundled CSV. The files are compiled in, so a parse failure is a build defect and panics in tests.
    pub(crate) fn parse(text: &str) -> SpectralTable {
        let mut lines = strip_utf8_bom(text).lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
        let header: Vec<String> =
            lines.next().expect("table header").split(',').map(|s| s.trim().to_string()).collect();
        let n = header.len() - 1;
        let mut wavelengths_nm = Vec::new();
        let mut columns = vec![Vec::new(); n];
        for line in lines {
            let mut fields = line.split(',').map(|f| f.trim().parse::<f64>().expect("numeric table entry"));
            wavelengths_nm.push(fields.next().expect("wavelength"));
            for col in columns.iter_mut() {
                col.push(fields.next().expect("table column"));
            }
        }
        SpectralTable { wavelengths_nm, columns, names: header[1..].to_vec() }
    }

    /// Column `col` linearly interpolated at `wavelength_nm`; clamped to the end values outside the table.
    pub fn interpolate(&self, col: usize, wavelength_nm: f64) -> f64 {
        let x = &self.wavelengths_nm;
        let y = &self.columns[col];
        if wavelength_nm <= x[0] {
            return y[0];
        }
        if wavelength_nm >= x[x.len() - 1] {
            return y[y.len() - 1];
        }
        let i = x.partition_point(|&w| w <= wavelength_nm) - 1;
        let t = (wavelength_nm - x[i]) / (x[i + 1] - x[i]);
        y[i] + t * (y[i + 1] - y[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_interpolate() {
        let t = SpectralTable::parse("# src\nwavelength_nm,a,b\n400,1,10\n402,3,20\n");
        assert_eq!(t.names, vec!["a", "b"]);
        assert_eq!(t.interpolate(0, 401.0), 2.0);
        assert_eq!(t.interpolate(1, 390.0), 10.0);
        assert_eq!(t.interpolate(1, 500.0), 20.0);
    }
}
