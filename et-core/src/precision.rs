//! IEEE 754 binary16 ("half") conversion, for the reduced-precision model storage option:
//! half the flash of f32 at about 3 significant digits. Round to nearest, ties to even.

/// Converts `x` to binary16 bits (round to nearest even; overflow becomes infinity, NaN stays NaN).
#[must_use]
pub fn f32_to_f16(x: f32) -> u16 {
    let b = x.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let exp = ((b >> 23) & 0xff) as i32;
    let man = b & 0x007f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if man != 0 { 0x0200 } else { 0 };
    }
    let e = exp - 127 + 15;
    if e >= 0x1f {
        return sign | 0x7c00;
    }
    if e <= 0 {
        // Subnormal (or zero) in binary16: n * 2^-24 with n = m >> (14 - e).
        if e < -10 {
            return sign;
        }
        let m = man | 0x0080_0000;
        let shift = (14 - e) as u32;
        let half = 1u32 << (shift - 1);
        let rem = m & ((1u32 << shift) - 1);
        let mut n = m >> shift;
        if rem > half || (rem == half && n & 1 == 1) {
            n += 1;
        }
        return sign | n as u16;
    }
    let mut h = ((e as u32) << 10) | (man >> 13);
    let rem = man & 0x1fff;
    if rem > 0x1000 || (rem == 0x1000 && h & 1 == 1) {
        h += 1; // may carry into the exponent, up to infinity: that is the right rounding
    }
    sign | h as u16
}

/// Converts binary16 bits to f32 (exact).
#[must_use]
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = u32::from(h & 0x8000) << 16;
    let exp = u32::from((h >> 10) & 0x1f);
    let man = u32::from(h & 0x03ff);
    let bits = match exp {
        0 if man == 0 => sign,
        0 => {
            // Subnormal: man * 2^-24.
            let v = man as f32 * f32::from_bits(0x3380_0000); // 2^-24
            return if sign != 0 { -v } else { v };
        }
        0x1f => sign | 0x7f80_0000 | (man << 13),
        _ => sign | ((exp + 112) << 23) | (man << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The magnitude of finite binary16 bits `h` by IEEE 754's definition, in f64 (exact):
    /// m x 2^-24 for exponent field 0, (1024 + m) x 2^(e - 25) otherwise. 0x7c00 (infinity)
    /// gives 2^16, the next step after the largest finite half, 65 504, as rounding sees it.
    fn magnitude(h: u16) -> f64 {
        let (e, m) = (i32::from((h >> 10) & 0x1f), f64::from(h & 0x3ff));
        if e == 0 {
            m * 2f64.powi(-24)
        } else {
            (1024.0 + m) * 2f64.powi(e - 25)
        }
    }

    /// The binary16 nearest `f` by the definition (ties to an even last bit; from 65 520 up,
    /// infinity), found by bisection over the ordered positive halves.
    fn nearest(f: f32) -> u16 {
        let sign = if f.is_sign_negative() { 0x8000 } else { 0 };
        let a = f64::from(f).abs();
        if a >= magnitude(0x7c00) {
            return sign | 0x7c00;
        }
        // The largest h with magnitude(h) <= a, then it or the next, whichever is nearer.
        let (mut lo, mut hi) = (0u16, 0x7c00u16);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if magnitude(mid) <= a {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (below, above) = (a - magnitude(lo), magnitude(hi) - a);
        sign | if below < above || (below == above && lo & 1 == 0) {
            lo
        } else {
            hi
        }
    }

    #[test]
    fn every_half_decodes_to_its_value_by_definition() {
        for h in 0..=u16::MAX {
            let got = f16_to_f32(h);
            let negative = h & 0x8000 != 0;
            if (h >> 10) & 0x1f == 0x1f {
                if h & 0x3ff == 0 {
                    assert!(
                        got.is_infinite() && got.is_sign_negative() == negative,
                        "{h:#x}"
                    );
                } else {
                    assert!(got.is_nan(), "{h:#x}");
                }
                continue;
            }
            assert_eq!(f64::from(got).abs(), magnitude(h), "{h:#x}");
            assert_eq!(got.is_sign_negative(), negative, "{h:#x}");
            assert_eq!(f32_to_f16(got), h, "round trip {h:#x}");
        }
    }

    #[test]
    fn encoding_rounds_to_the_nearest_half_ties_to_even() {
        // A deterministic sweep over f32 bit patterns, dense enough to hit every exponent and
        // the rounding boundaries (ties included, via the low mantissa bits).
        let mut rng = crate::rng::Rng::new(0x1234_5678);
        for i in 0..2_000_000u32 {
            let x = rng.next_u32();
            let bits = if i % 4 == 0 {
                x & 0xffff_e000 | 0x1000
            } else {
                x
            };
            let f = f32::from_bits(bits);
            let got = f32_to_f16(f);
            if f.is_nan() {
                assert!(f16_to_f32(got).is_nan(), "{bits:#x}");
            } else {
                assert_eq!(got, nearest(f), "{f:e} ({bits:#x})");
            }
        }
        // The boundaries by name: the largest half, the tie above it, the smallest subnormal
        // and the tie below it (to zero, the even neighbour).
        assert_eq!(f32_to_f16(65_504.0), 0x7bff);
        assert_eq!(f32_to_f16(65_519.99), 0x7bff);
        assert_eq!(f32_to_f16(65_520.0), 0x7c00);
        assert_eq!(f32_to_f16(2f32.powi(-24)), 0x0001);
        assert_eq!(f32_to_f16(2f32.powi(-25)), 0x0000);
        assert_eq!(f32_to_f16(-2f32.powi(-25)), 0x8000);
    }
}
