//! exp for the CPU's training passes over every voxel of a crop (the cross-entropy's value and
//! gradient, the background gate): a polynomial with no table or branch, so a loop over a slice
//! runs several lanes at once, where libm's `expf` takes one value per call. Within 2 ulp of
//! `f32::exp` (tests/grounded.rs); inference keeps `f32::exp` (its labels are the tensor
//! formulation's bits).

const LOG2E: f32 = std::f32::consts::LOG2_E;
/// ln 2 in two parts: `n * LN2_HI` is exact for |n| < 2^9.
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;
/// 1.5 * 2^23: adding and subtracting it rounds to the nearest whole number.
const ROUND: f32 = 12_582_912.0;

/// e^x; `x` below -87.3 gives about 2^-126 instead of a subnormal, NaN stays NaN.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    let x = x.clamp(-87.3, 88.0);
    let t = x * LOG2E + ROUND;
    let n = t - ROUND;
    let r = x - n * LN2_HI - n * LN2_LO;
    // Cephes' expf polynomial for e^r on |r| <= ln 2 / 2.
    let mut p = 1.987_569_1e-4f32;
    p = p * r + 1.398_199_9e-3;
    p = p * r + 8.333_452e-3;
    p = p * r + 4.166_579_6e-2;
    p = p * r + 1.666_666_5e-1;
    p = p * r + 0.5;
    let e = p * r * r + r + 1.0;
    // 2^n from the bits of `t`, whose low mantissa bits hold n (integer lanes, where a float
    // to integer cast would take one value at a time).
    let k = t.to_bits().wrapping_sub(ROUND.to_bits());
    f32::from_bits(k.wrapping_add(127) << 23) * e
}

/// `v[i] = exp(v[i])` for every element.
#[inline]
pub fn exp_in_place(v: &mut [f32]) {
    for x in v {
        *x = exp(*x);
    }
}

/// `out = exp(l - max(l))` for each row `l` of `width` values of `rows` (softmax's numerators),
/// each row's maximum in `maxes` (cleared first).
pub fn shifted_exp(rows: &[f32], width: usize, out: &mut [f32], maxes: &mut Vec<f32>) {
    maxes.clear();
    for (o, l) in out.chunks_exact_mut(width).zip(rows.chunks_exact(width)) {
        let max = l.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        for (o, &v) in o.iter_mut().zip(l) {
            *o = v - max;
        }
        maxes.push(max);
    }
    exp_in_place(out);
}
