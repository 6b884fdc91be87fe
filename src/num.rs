//! Numbers in messages as a person reads them: the shortest digits that read back as
//! the same double (so a printed bound, pasted back, is the bound exactly), in exponent
//! form when very large or small (`1e308`, not 309 digits); and angles wrapped.
use std::f64::consts::{PI, TAU};
use std::fmt;

/// `x` wrapped into (−π, π].
pub fn wrap_pi(x: f64) -> f64 {
    let y = x.rem_euclid(TAU);
    if y > PI { y - TAU } else { y }
}

/// Displays an `f64` readably (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        let a = x.abs();
        // Both forms are Rust's shortest round-trip digits.
        if a != 0.0 && a.is_finite() && !(1e-4..1e6).contains(&a) {
            write!(f, "{x:e}")
        } else {
            write!(f, "{x}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Num;

    #[test]
    fn short_exact_and_readable() {
        assert_eq!(Num(1e308).to_string(), "1e308");
        assert_eq!(Num(-1.5e-7).to_string(), "-1.5e-7");
        assert_eq!(Num(60.0).to_string(), "60");
        assert_eq!(Num(0.001).to_string(), "0.001");
        assert_eq!(Num(f64::INFINITY).to_string(), "inf");
        for x in [std::f64::consts::FRAC_PI_2, 60f64.next_up(), 1e-300, 7e22] {
            assert_eq!(Num(x).to_string().parse::<f64>().unwrap(), x, "{x}");
        }
    }
}
