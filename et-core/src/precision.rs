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

    #[test]
    fn every_half_decodes_like_the_half_crate() {
        for h in 0..=u16::MAX {
            let want = half::f16::from_bits(h).to_f32();
            let got = f16_to_f32(h);
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "{h:#x}"
            );
            if !got.is_nan() {
                assert_eq!(f32_to_f16(got), h, "round trip {h:#x}");
            }
        }
    }

    #[test]
    fn encoding_rounds_like_the_half_crate() {
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
            let want = half::f16::from_f32(f);
            let got = f32_to_f16(f);
            if want.is_nan() {
                assert!(f16_to_f32(got).is_nan());
            } else {
                assert_eq!(got, want.to_bits(), "{f:e} ({bits:#x})");
            }
        }
    }
}
