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
/// each row's maximum in `maxes` (cleared first). On x86-64 CPUs with AVX2 the same code runs
/// compiled for them (eight lanes where the baseline has four): the same IEEE operations in the
/// same order (Rust never fuses a multiply and an add), so the same bits.
pub fn shifted_exp(rows: &[f32], width: usize, out: &mut [f32], maxes: &mut Vec<f32>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above: the one requirement of the callee.
        return unsafe { shifted_exp_avx2(rows, width, out, maxes) };
    }
    shifted_exp_body(rows, width, out, maxes);
}

/// `shifted_exp_body` compiled with AVX2 (`shifted_exp`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn shifted_exp_avx2(rows: &[f32], width: usize, out: &mut [f32], maxes: &mut Vec<f32>) {
    shifted_exp_body(rows, width, out, maxes);
}

#[inline(always)]
fn shifted_exp_body(rows: &[f32], width: usize, out: &mut [f32], maxes: &mut Vec<f32>) {
    maxes.clear();
    if width == 9 {
        // The label rows (the callers'): each row's maximum as a tree of compares, independent
        // of one another, where a fold of `f32::max` is a chain of nine with a NaN check each.
        // The same maximum (only a zero's sign can differ, and `v - 0.0`, `v + 0.0` agree) for
        // rows without NaN; a row with NaN gives NaN either way.
        for (o, l) in out.as_chunks_mut::<9>().0.iter_mut().zip(rows.as_chunks::<9>().0) {
            let m = |a: f32, b: f32| if a > b { a } else { b };
            let max = m(m(m(l[0], l[1]), m(l[2], l[3])), m(m(l[4], l[5]), m(l[6], l[7])));
            let max = m(max, l[8]);
            for (o, &v) in o.iter_mut().zip(l) {
                *o = v - max;
            }
            maxes.push(max);
        }
    } else {
        for (o, l) in out.chunks_exact_mut(width).zip(rows.chunks_exact(width)) {
            let max = l.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            for (o, &v) in o.iter_mut().zip(l) {
                *o = v - max;
            }
            maxes.push(max);
        }
    }
    for x in out {
        *x = exp(*x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both widths' paths give the bits of `fold(f32::max)` and `exp` row by row, with ties,
    /// signed zeros and infinities among the values.
    #[test]
    fn shifted_exp_matches_the_plain_rows() {
        let special = [0.0, -0.0, f32::NEG_INFINITY, 3.5, -3.5, 80.0, -100.0];
        for width in [9, 5] {
            let rows: Vec<f32> = (0..width * 300)
                .map(|i: usize| {
                    let h = (i as u32).wrapping_mul(2_654_435_761) >> 8;
                    if h.is_multiple_of(5) {
                        special[(h as usize / 5) % special.len()]
                    } else {
                        (h % 4000) as f32 / 100.0 - 20.0
                    }
                })
                .collect();
            let (mut out, mut maxes) = (vec![0f32; rows.len()], Vec::new());
            shifted_exp(&rows, width, &mut out, &mut maxes);
            for (r, l) in rows.chunks_exact(width).enumerate() {
                let max = l.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                assert_eq!(maxes[r], max, "row {r}");
                for (c, &v) in l.iter().enumerate() {
                    assert_eq!(out[r * width + c].to_bits(), exp(v - max).to_bits(), "row {r} column {c}");
                }
            }
        }
    }
}
