//! Decoding a fuzzer's bytes into numbers. Each value first reads a selector byte: most values fall in the range a
//! caller would plausibly pass and somewhat beyond (log-uniform or uniform from two bytes), some are special values
//! (zero, negative zero, infinities, NaN, subnormals, extremes) and some are raw IEEE bit patterns, so the targets
//! reach both the core's arithmetic and its input checks. Exhausted input reads as zeros.

#![allow(dead_code)] // each target uses part of it

pub struct Bytes<'a> {
    data: &'a [u8],
}

/// Values outside every accepted range and at the edges of floating point.
const SPECIAL: [f64; 12] = [
    0.0,
    -0.0,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e-310, // subnormal
    f64::MIN_POSITIVE,
    f64::MAX,
    -1.0,
    1.0,
    1e-300,
    1e300,
];

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data }
    }

    pub fn byte(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes([self.byte(), self.byte()])
    }

    fn raw_f64(&mut self) -> f64 {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.byte();
        }
        f64::from_le_bytes(b)
    }

    /// A fraction in [0, 1] from two bytes.
    pub fn unit(&mut self) -> f64 {
        f64::from(self.u16()) / 65535.0
    }

    /// 10^x for x uniform in [lo, hi] (selector 0..=199), a special value (200..=239) or raw bits (240..).
    pub fn log_value(&mut self, lo: f64, hi: f64) -> f64 {
        match self.byte() {
            s @ 0..=199 => {
                let v = 10f64.powf(lo + (hi - lo) * self.unit());
                if s % 50 == 49 {
                    -v
                } else {
                    v
                }
            }
            s @ 200..=239 => SPECIAL[usize::from(s - 200) % SPECIAL.len()],
            _ => self.raw_f64(),
        }
    }

    /// Uniform in [lo, hi] (selector 0..=199), a special value or raw bits, as for [`Bytes::log_value`].
    pub fn linear(&mut self, lo: f64, hi: f64) -> f64 {
        match self.byte() {
            0..=199 => lo + (hi - lo) * self.unit(),
            s @ 200..=239 => SPECIAL[usize::from(s - 200) % SPECIAL.len()],
            _ => self.raw_f64(),
        }
    }

    /// The bytes not read yet.
    pub fn rest(&self) -> &'a [u8] {
        self.data
    }
}
