//! A raw deflate coder for arrays made of runs, with the CRC-32 a zip member needs computed in
//! the same pass. Like zlib's RLE strategy it codes each byte as a literal or as a run of the
//! previous byte (a match at distance 1) and searches for nothing else, but it has no window or
//! hash chains to keep (zlib slides them every 32 kB), finds runs 32 bytes at a step, and feeds
//! runs of zeros to the CRC arithmetically (appending n zero bytes multiplies the CRC register by
//! x^(8n) modulo the polynomial) instead of byte by byte. Blocks use dynamic Huffman codes, so a
//! run of 258 zeros costs a few bits. BEV frames are mostly long runs of zeros (docs/benchmarks.md,
//! `bench npz`).

/// Tokens per block: a literal byte (< 256) or `MATCH + length` (a run of 3..=258 at distance 1).
const BLOCK: usize = 1 << 14;
const MATCH: u16 = 256;
const MAX_RUN: usize = 258;
/// Token values: 256 literals, then `MATCH + length` up to the longest run.
const TOKENS: usize = MATCH as usize + MAX_RUN + 1;
/// Zero runs at least this long enter the CRC by multiplication; shorter ones cost less byte by
/// byte (crc32fast folds some 10 bytes per nanosecond; a multiplication costs about 0.3 us).
const ZERO_SKIP: usize = 4096;

/// The coder of one member: `write` its bytes in order, then `finish`.
pub struct RunCoder {
    tokens: Vec<u16>,
    /// How often each token value occurs in `tokens`.
    counts: Vec<u32>,
    bits: Bits,
    crc: crc32fast::Hasher,
}

impl Default for RunCoder {
    fn default() -> Self {
        Self {
            tokens: Vec::with_capacity(BLOCK + 2 * MAX_RUN),
            counts: vec![0; TOKENS],
            bits: Bits::default(),
            crc: crc32fast::Hasher::new(),
        }
    }
}

impl RunCoder {
    /// Code `data`. Runs do not reach back into earlier calls' bytes, so call it with large slices.
    pub fn write(&mut self, data: &[u8]) {
        let (mut i, mut crc_from) = (0, 0);
        while i < data.len() {
            let b = data[i];
            let end = run_end(data, i + 1, b);
            let mut left = end - i - 1;
            // A literal, then the run as matches; a remainder under 3 bytes as literals.
            let literals = 1 + left % MAX_RUN * usize::from(left % MAX_RUN < 3);
            left -= literals - 1;
            self.tokens.extend(std::iter::repeat_n(u16::from(b), literals));
            self.counts[b as usize] += literals as u32;
            while left > 0 {
                let n = left.min(MAX_RUN);
                self.tokens.push(MATCH + n as u16);
                self.counts[MATCH as usize + n] += 1;
                left -= n;
            }
            if b == 0 && end - i >= ZERO_SKIP {
                self.crc.update(&data[crc_from..i]);
                self.crc = crc32fast::Hasher::new_with_initial(append_zeros(self.crc.clone().finalize(), end - i));
                crc_from = end;
            }
            i = end;
            if self.tokens.len() >= BLOCK {
                self.block(false);
            }
        }
        self.crc.update(&data[crc_from..]);
    }

    /// The raw deflate stream and the CRC-32 of every byte written.
    pub fn finish(mut self) -> (Vec<u8>, u32) {
        self.block(true);
        (self.bits.finish(), self.crc.finalize())
    }

    /// Write the buffered tokens as one dynamic-Huffman block.
    fn block(&mut self, last: bool) {
        let mut freq = [0u32; 286];
        freq[256] = 1;
        for (t, &c) in self.counts.iter().enumerate() {
            freq[symbol(t)] += c;
        }
        let mut lit_len = [0u8; 286];
        code_lengths(&freq, 15, &mut lit_len);
        let n_lit = 257.max(lit_len.iter().rposition(|&l| l > 0).map_or(0, |p| p + 1));
        // Distance code 0 (distance 1) is the only one used; code 1 completes the code.
        let dist_len = [1u8, 1];
        let mut lens = lit_len[..n_lit].to_vec();
        lens.extend_from_slice(&dist_len);
        let header = rle_lengths(&lens);
        let mut cl_freq = [0u32; 19];
        for &(s, _) in &header {
            cl_freq[s as usize] += 1;
        }
        let mut cl_len = [0u8; 19];
        code_lengths(&cl_freq, 7, &mut cl_len);
        let n_cl = 4.max(CL_ORDER.iter().rposition(|&s| cl_len[s] > 0).map_or(0, |p| p + 1));

        let b = &mut self.bits;
        b.put(u64::from(last) | (2 << 1), 3);
        b.put((n_lit - 257) as u64 | ((dist_len.len() - 1) as u64) << 5 | ((n_cl - 4) as u64) << 10, 14);
        for &s in &CL_ORDER[..n_cl] {
            b.put(cl_len[s].into(), 3);
        }
        let cl_code = canonical(&cl_len);
        for &(s, extra) in &header {
            let s = s as usize;
            b.put(cl_code[s].into(), cl_len[s].into());
            let n_extra = match s {
                16 => 2,
                17 => 3,
                18 => 7,
                _ => 0,
            };
            b.put(extra.into(), n_extra);
        }
        let code = canonical(&lit_len);
        let dist_code = canonical(&dist_len)[0];
        // Each token's whole bit string: a literal's code, or a length code, its extra bits and
        // the distance code.
        let mut table = [(0u32, 0u32); TOKENS];
        for (t, e) in table.iter_mut().enumerate().filter(|(t, _)| *t < 256 || *t >= MATCH as usize + 3) {
            let s = symbol(t);
            *e = (code[s].into(), lit_len[s].into());
            if t >= MATCH as usize {
                let c = s - 257;
                let extra = (t - MATCH as usize - LEN_BASE[c] as usize) as u32;
                e.0 |= (extra | u32::from(dist_code) << LEN_EXTRA[c]) << e.1;
                e.1 += u32::from(LEN_EXTRA[c] + dist_len[0]);
            }
        }
        for &t in &self.tokens {
            let (v, n) = table[t as usize];
            b.put(v.into(), n);
        }
        b.put(code[256].into(), lit_len[256].into());
        self.tokens.clear();
        self.counts.fill(0);
    }
}

/// The lit/len symbol of a token.
fn symbol(t: usize) -> usize {
    if t < MATCH as usize { t } else { 257 + LEN_CODE[t - MATCH as usize] as usize }
}

/// The first index from `j` on where `data` stops repeating `b` (`data.len()` if it never does).
fn run_end(data: &[u8], mut j: usize, b: u8) -> usize {
    let pat = u64::from_ne_bytes([b; 8]);
    let word = |k: usize| u64::from_le_bytes(data[k..k + 8].try_into().unwrap_or_default()) ^ pat;
    // 32 bytes a step through long runs, then the first differing byte of the differing word.
    while j + 32 <= data.len() && (word(j) | word(j + 8) | word(j + 16) | word(j + 24)) == 0 {
        j += 32;
    }
    while j + 8 <= data.len() {
        let x = word(j);
        if x != 0 {
            return j + (x.trailing_zeros() / 8) as usize;
        }
        j += 8;
    }
    j + data[j..].iter().take_while(|&&x| x == b).count()
}

/// Deflate's bit order: least significant bit first.
#[derive(Default)]
struct Bits {
    out: Vec<u8>,
    acc: u64,
    n: u32,
}

impl Bits {
    /// Append the `len` (at most 32) low bits of `v`.
    fn put(&mut self, v: u64, len: u32) {
        self.acc |= v << self.n;
        self.n += len;
        if self.n >= 32 {
            self.out.extend_from_slice(&(self.acc as u32).to_le_bytes());
            self.acc >>= 32;
            self.n -= 32;
        }
    }

    fn finish(mut self) -> Vec<u8> {
        let bytes = self.n.div_ceil(8) as usize;
        self.out.extend_from_slice(&self.acc.to_le_bytes()[..bytes]);
        self.out
    }
}

/// Huffman code lengths of at most `limit` bits for `freq` (0 for unused symbols; at least two
/// symbols get a code, as inflaters want a complete code). Over the limit, the frequencies are
/// halved and the tree built again: the flatter tree is shallower.
fn code_lengths(freq: &[u32], limit: u8, lens: &mut [u8]) {
    let mut f = freq.to_vec();
    for s in 0..f.len() {
        if f.iter().filter(|&&x| x > 0).count() >= 2 {
            break;
        }
        f[s] = f[s].max(1);
    }
    loop {
        huffman_depths(&f, lens);
        if lens.iter().all(|&l| l <= limit) {
            return;
        }
        for x in f.iter_mut().filter(|x| **x > 0) {
            *x = (*x >> 1).max(1);
        }
    }
}

/// Depth of each leaf of a Huffman tree of `f` (two-queue construction, ties broken by symbol,
/// so the lengths depend only on the frequencies).
fn huffman_depths(f: &[u32], lens: &mut [u8]) {
    let mut leaves: Vec<(u32, usize)> = f.iter().enumerate().filter(|(_, x)| **x > 0).map(|(s, &x)| (x, s)).collect();
    leaves.sort_unstable();
    let n = leaves.len();
    // Nodes 0..n are the leaves in order, n.. the internal nodes as made; a parent comes after
    // its children.
    let mut weight: Vec<u64> = leaves.iter().map(|l| u64::from(l.0)).collect();
    let mut parent = vec![0usize; 2 * n - 1];
    let (mut leaf, mut inner) = (0, n);
    for k in n..2 * n - 1 {
        let mut take = || {
            let from_leaf = leaf < n && (inner >= k || weight[leaf] <= weight[inner]);
            let x = if from_leaf { &mut leaf } else { &mut inner };
            *x += 1;
            *x - 1
        };
        let (a, b) = (take(), take());
        weight.push(weight[a] + weight[b]);
        parent[a] = k;
        parent[b] = k;
    }
    let mut depth = vec![0u8; 2 * n - 1];
    for k in (0..2 * n - 2).rev() {
        depth[k] = depth[parent[k]].saturating_add(1);
    }
    lens.fill(0);
    for (k, &(_, s)) in leaves.iter().enumerate() {
        lens[s] = depth[k];
    }
}

/// Canonical codes for `lens` (RFC 1951 3.2.2), bit-reversed for writing least significant first.
fn canonical(lens: &[u8]) -> Vec<u16> {
    let mut count = [0u16; 16];
    for &l in lens {
        count[l as usize] += 1;
    }
    count[0] = 0;
    let mut next = [0u16; 16];
    for l in 1..16 {
        next[l] = (next[l - 1] + count[l - 1]) << 1;
    }
    lens.iter()
        .map(|&l| {
            if l == 0 {
                return 0;
            }
            let c = next[l as usize];
            next[l as usize] += 1;
            c.reverse_bits() >> (16 - l)
        })
        .collect()
}

/// Code lengths as the code-length alphabet writes them: (symbol, extra bits); 16 repeats the
/// previous length 3-6 times, 17 and 18 code 3-10 and 11-138 zeros.
fn rle_lengths(lens: &[u8]) -> Vec<(u8, u8)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < lens.len() {
        let l = lens[i];
        let run = lens[i..].iter().take_while(|&&x| x == l).count();
        let mut left = run;
        if l == 0 {
            while left >= 11 {
                let n = left.min(138);
                out.push((18, (n - 11) as u8));
                left -= n;
            }
            if left >= 3 {
                out.push((17, (left - 3) as u8));
                left = 0;
            }
        } else {
            out.push((l, 0));
            left -= 1;
            while left >= 3 {
                let n = left.min(6);
                out.push((16, (n - 3) as u8));
                left -= n;
            }
        }
        out.extend(std::iter::repeat_n((l, 0), left));
        i += run;
    }
    out
}

/// The order code-length code lengths are written in (RFC 1951 3.2.7).
const CL_ORDER: [usize; 19] = [16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15];
/// Length codes 257.. : base length and extra bits.
const LEN_BASE: [u16; 29] =
    [3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258];
const LEN_EXTRA: [u8; 29] = [0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0];
/// The length code (minus 257) of each run length 0..=258.
const LEN_CODE: [u8; 259] = {
    let mut t = [0u8; 259];
    let mut n = 3;
    while n <= MAX_RUN {
        let mut c = 28;
        while LEN_BASE[c] as usize > n {
            c -= 1;
        }
        t[n] = c as u8;
        n += 1;
    }
    t
};

/// The reflected CRC-32 polynomial.
const POLY: u32 = 0xedb8_8320;

/// a * b modulo the polynomial, both in the reflected order (x^0 is the top bit).
fn mul_mod(a: u32, mut b: u32) -> u32 {
    let mut p = 0;
    for k in (0..32).rev() {
        if a & (1 << k) != 0 {
            p ^= b;
        }
        b = if b & 1 != 0 { (b >> 1) ^ POLY } else { b >> 1 };
    }
    p
}

/// x^(2^k) modulo the polynomial, k = 0..64.
fn x_pow2() -> &'static [u32; 64] {
    static T: std::sync::OnceLock<[u32; 64]> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let mut t = [0u32; 64];
        t[0] = 1 << 30; // x^1
        for k in 1..64 {
            t[k] = mul_mod(t[k - 1], t[k - 1]);
        }
        t
    })
}

/// The CRC-32 of the bytes `crc` covers followed by `n` zero bytes: the register (the CRC
/// inverted) times x^(8n).
pub fn append_zeros(crc: u32, n: usize) -> u32 {
    let t = x_pow2();
    let (mut p, mut n, mut k) = (1u32 << 31, n as u64, 3);
    while n != 0 {
        if n & 1 != 0 {
            p = mul_mod(t[k], p);
        }
        n >>= 1;
        k += 1;
    }
    !mul_mod(p, !crc)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inflate(raw: &[u8]) -> Vec<u8> {
        miniz_oxide::inflate::decompress_to_vec(raw).expect("a valid raw deflate stream")
    }

    fn round_trip(parts: &[&[u8]]) {
        let mut z = RunCoder::default();
        for p in parts {
            z.write(p);
        }
        let (raw, crc) = z.finish();
        let all = parts.concat();
        assert_eq!(inflate(&raw), all);
        assert_eq!(crc, crc32fast::hash(&all));
    }

    #[test]
    fn runs_literals_and_empty_input_round_trip() {
        round_trip(&[]);
        round_trip(&[&[]]);
        round_trip(&[&[7]]);
        round_trip(&[&[0; 3], &[1, 1, 2, 2, 2, 2]]);
        let mut mixed = vec![0u8; 300_000];
        for (i, x) in mixed.iter_mut().enumerate() {
            // Zero runs of every length around the CRC threshold, runs of ones, and noise.
            *x = match i % 20_011 {
                k if k < 3 => (i % 7) as u8,
                k if k < 9_000 => 0,
                k if k < 9_300 => 1,
                _ => (i.wrapping_mul(2_654_435_761) >> 13) as u8 & if i % 3 == 0 { 0xff } else { 0 },
            };
        }
        round_trip(&[&mixed[..1000], &mixed[1000..]]);
        // Every byte value equally often: long literal stretches, deep and flat Huffman codes.
        let noise: Vec<u8> = (0..200_000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8).collect();
        round_trip(&[&noise]);
    }

    #[test]
    fn skewed_frequencies_keep_codes_within_15_bits() {
        // Fibonacci frequencies make a Huffman tree as deep as it can be.
        let (mut a, mut b) = (1u32, 1u32);
        let mut freq = vec![];
        for _ in 0..30 {
            freq.push(a);
            (a, b) = (b, a + b);
        }
        let mut lens = vec![0u8; freq.len()];
        code_lengths(&freq, 15, &mut lens);
        assert!(lens.iter().all(|&l| (1..=15).contains(&l)), "{lens:?}");
        let kraft: f64 = lens.iter().map(|&l| 0.5f64.powi(l.into())).sum();
        assert!(kraft <= 1.0);
        let mut data = vec![];
        for (s, &f) in freq.iter().enumerate().take(20) {
            data.extend(std::iter::repeat_n(s as u8 * 5 + 1, (f as usize).min(5000)));
            data.push(s as u8);
        }
        round_trip(&[&data]);
    }

    #[test]
    fn appending_zeros_matches_hashing_them() {
        let head = b"numpy header";
        for n in [0, 1, 7, 4096, 100_003] {
            let mut all = head.to_vec();
            all.resize(head.len() + n, 0);
            assert_eq!(append_zeros(crc32fast::hash(head), n), crc32fast::hash(&all), "{n}");
        }
    }
}
