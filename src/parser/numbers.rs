//! The numbers of a scene file: correctly rounded floats, pbrt-v4's strict integers,
//! and long number lists read on all threads.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  1 1 0 ... ]   # 50 MB of numbers
//!     "integer indices" [ 0 1 2 ... ]
//! ```
//!
//! A list of more than [`PARALLEL_LIST_BYTES`] of text is cut at whitespace into pieces;
//! the words of each piece are counted, then parsed straight into their places in the
//! parameter's array, both on all threads. Any word that is not a plain number of the
//! list's kind (a comment, a string, a bracket, a bad number) hands the whole list back
//! to the sequential reader, which reports it at its line and column.

use super::lexer::is_space;
use super::params::Values;
use std::mem::MaybeUninit;

/// Number lists at least this long (in bytes) are parsed in parallel pieces.
const PARALLEL_LIST_BYTES: usize = 1 << 20;
const PIECE_BYTES: usize = 1 << 18;

/// A kind of number a long list holds.
trait ListNumber: Sized + Send {
    /// Reads one number whose text starts at `text[at]` (not whitespace) and runs to the
    /// next whitespace byte or the end: the number and where its text ends.
    fn scan(text: &[u8], at: usize) -> Option<(Self, usize)>;
}

impl ListNumber for f32 {
    #[inline(always)]
    fn scan(text: &[u8], at: usize) -> Option<(f32, usize)> {
        if let Some(read) = word_f32(text, at) {
            return Some(read);
        }
        if let Some(read) = short_f32(text, at) {
            return Some(read);
        }
        match fast_f32(text, at) {
            Ok(read) => Some(read),
            Err(end) => Some((standard(&text[at..end])?, end)),
        }
    }
}

impl ListNumber for i32 {
    #[inline(always)]
    fn scan(text: &[u8], at: usize) -> Option<(i32, usize)> {
        // The usual index: 1 to 7 digits and whitespace, read as one 8-byte word.
        if let Some(&bytes) = text.get(at..).and_then(|t| t.first_chunk::<8>()) {
            let bytes = u64::from_le_bytes(bytes);
            let (n, v) = digit_run(bytes);
            if (1..8).contains(&n) && is_space((bytes >> (8 * n)) as u8) {
                return Some((v as i32, at + n));
            }
        }
        scan_int(text, at)
    }
}

/// The commonest coordinate: an optional minus, then at most 8 bytes of digits with a
/// point among them (`0.008598`, `-12.375`), then whitespace or the text's end. One
/// 8-byte word holds it all: the point is taken out and the digits, at most 7, read
/// as one run, then rounded as in [`short_f32`].
#[inline(always)]
fn word_f32(text: &[u8], at: usize) -> Option<(f32, usize)> {
    const LANES: u64 = 0x0101_0101_0101_0101;
    let neg = text.get(at) == Some(&b'-');
    let from = at + neg as usize;
    let bytes = u64::from_le_bytes(*text.get(from..)?.first_chunk::<8>()?);
    let x = bytes ^ (b'0' as u64 * LANES);
    let not_digit = (((x & (0x7f * LANES)) + (0x76 * LANES)) | x) & (0x80 * LANES);
    let point = not_digit.trailing_zeros() / 8;
    if point == 8 || (bytes >> (8 * point)) as u8 != b'.' {
        return None;
    }
    // The first byte after the point that is not a digit ends the number (8: none in
    // the word, so the byte after it must be whitespace or nothing).
    let end = (not_digit & (not_digit - 1)).trailing_zeros() / 8;
    let ends = match end {
        8 => text.get(from + 8).is_none_or(|&c| is_space(c)),
        _ => is_space((bytes >> (8 * end)) as u8),
    };
    let digits = end - 1;
    if !ends || digits == 0 {
        return None;
    }
    // The digits above the point move down one byte into its place.
    let below = (1u64 << (8 * point)) - 1;
    let joined = (x & below) | ((x >> 8) & !below);
    let v = short_quotient(digit_value(joined, digits), (end - point - 1) as usize);
    Some((if neg { -v } else { v }, from + end as usize))
}

/// The usual coordinate, `-12.375`: an optional minus, up to 7 digits, a point and up
/// to 7 digits, then whitespace, read as two 8-byte words, and correctly rounded (see
/// [`short_quotient`]); `None` for anything else.
#[inline(always)]
fn short_f32(text: &[u8], at: usize) -> Option<(f32, usize)> {
    const POW10: [u64; 8] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000];
    let word = |i: usize| text.get(i..).and_then(|t| t.first_chunk::<8>()).map(|b| u64::from_le_bytes(*b));
    let neg = text.get(at) == Some(&b'-');
    let from = at + neg as usize;
    let whole_bytes = word(from)?;
    let (n1, whole) = digit_run(whole_bytes);
    let after = (whole_bytes >> (8 * n1.min(7))) as u8;
    let (n2, fraction, end) = match after {
        b'.' if n1 < 8 => {
            let bytes = word(from + n1 + 1)?;
            let (n2, fraction) = digit_run(bytes);
            (n2 < 8 && is_space((bytes >> (8 * n2.min(7))) as u8)).then_some((n2, fraction, from + n1 + 1 + n2))?
        }
        c if n1 < 8 && is_space(c) => (0, 0, from + n1),
        _ => return None,
    };
    let mantissa = whole * POW10[n2] + fraction;
    if n1 + n2 == 0 || mantissa > 1 << 24 {
        return None;
    }
    let v = short_quotient(mantissa, n2);
    Some((if neg { -v } else { v }, end))
}

/// A long list of plain numbers (`text` starts inside its brackets) parsed by pieces on
/// all threads: the text up to the first `]`. Returns the offset of that `]`, or `None`,
/// having pushed nothing, when any word is not a number of the list's kind: the
/// sequential reader then meets it and reports it.
pub fn parallel_numbers(text: &[u8], values: &mut Values) -> Option<usize> {
    let close = find_close(text)?;
    if close < PARALLEL_LIST_BYTES {
        return None;
    }
    let pieces = pieces_at_spaces(&text[..close], PIECE_BYTES);
    match values {
        Values::Floats(v) => parse_pieces(&pieces, v)?,
        Values::Ints(v) => parse_pieces(&pieces, v)?,
        _ => return None,
    }
    Some(close)
}

/// Where the first `]` is: looked for in the first [`PARALLEL_LIST_BYTES`] at once,
/// and past them (a long list) in pairs of pieces as long, one on each thread, in
/// order, so that at most one piece is read past it. (One search through a 30 MB list
/// took 1.2 ms of a 50 MB file's 50.)
fn find_close(text: &[u8]) -> Option<usize> {
    let mut start = text.len().min(PARALLEL_LIST_BYTES);
    if let Some(at) = memchr::memchr(b']', &text[..start]) {
        return Some(at);
    }
    for pair in text[start..].chunks(2 * PARALLEL_LIST_BYTES) {
        let (a, b) = pair.split_at(pair.len().min(PARALLEL_LIST_BYTES));
        let (in_a, in_b) = rayon::join(|| memchr::memchr(b']', a), || memchr::memchr(b']', b));
        if let Some(at) = in_a.or(in_b.map(|k| a.len() + k)) {
            return Some(start + at);
        }
        start += pair.len();
    }
    None
}

/// Appends the numbers of `pieces`, in order, to `out`; `None` (and `out` as it was)
/// when a word is not a number.
fn parse_pieces<T: ListNumber>(pieces: &[&[u8]], out: &mut Vec<T>) -> Option<()> {
    use rayon::prelude::*;
    let counts: Vec<usize> = pieces.par_iter().map(|p| count_words(p)).collect();
    let total: usize = counts.iter().sum();
    if out.capacity() - out.len() < total {
        // Pages huge from their first write: a fault per 2 MiB instead of per 4 KiB
        // (`check` of a 49 MB inline mesh in 0.89 of the time, under a hypervisor),
        // and the accelerator's folding of mesh arrays into huge pages has nothing
        // left to copy.
        let mut grown = crate::hugepages::with_capacity(out.len() + total);
        grown.append(out);
        *out = grown;
    }
    let mut rest = &mut out.spare_capacity_mut()[..total];
    let mut slots = Vec::with_capacity(pieces.len());
    for &n in &counts {
        let (slot, tail) = rest.split_at_mut(n);
        slots.push(slot);
        rest = tail;
    }
    pieces.par_iter().zip(slots).try_for_each(|(piece, slot)| parse_into(piece, slot))?;
    // SAFETY: every piece returned `Some`, so each wrote its whole slot, and the slots
    // tile the first `total` places after the vector's length.
    unsafe { out.set_len(out.len() + total) };
    Some(())
}

/// `text` cut into pieces of about `size` bytes, each ending just before a whitespace
/// byte (so no word is split).
fn pieces_at_spaces(text: &[u8], size: usize) -> Vec<&[u8]> {
    let mut pieces = Vec::with_capacity(text.len() / size + 1);
    let mut rest = text;
    while rest.len() > size {
        let cut = rest[size..].iter().position(|&c| is_space(c)).map_or(rest.len(), |k| size + k);
        let (piece, tail) = rest.split_at(cut);
        pieces.push(piece);
        rest = tail;
    }
    pieces.push(rest);
    pieces
}

/// How many whitespace-separated words `text` holds: the word starts of
/// [`start_masks`], counted 64 bytes at a time.
fn count_words(text: &[u8]) -> usize {
    start_masks(text).map(|(_, starts)| starts.count_ones() as usize).sum()
}

/// Parses the words of `text` into `out`, which has room for exactly as many; `None`
/// at the first word that is not a number. Each word's start is read off a mask of the
/// whitespace, the one its count came from.
fn parse_into<T: ListNumber>(text: &[u8], out: &mut [MaybeUninit<T>]) -> Option<()> {
    let mut n = 0;
    for (base, mut starts) in start_masks(text) {
        while starts != 0 {
            let at = base + starts.trailing_zeros() as usize;
            starts &= starts - 1;
            // A number's reader ends it at whitespace or the text's end, so each word
            // is read whole or refused.
            let (value, _) = T::scan(text, at)?;
            out.get_mut(n)?.write(value);
            n += 1;
        }
    }
    (n == out.len()).then_some(())
}

/// For each 64-byte block of `text`, in order: where it starts, and a bit for each of
/// its bytes that begins a word (not whitespace, and first or after whitespace).
#[inline(always)]
fn start_masks(text: &[u8]) -> impl Iterator<Item = (usize, u64)> + '_ {
    let (blocks, tail) = text.as_chunks::<64>();
    let mut last = [b' '; 64];
    last[..tail.len()].copy_from_slice(tail);
    let last = (!tail.is_empty()).then_some(last);
    // Whether the byte before the block is whitespace (the text's start counts as it).
    let mut space_before = 1;
    blocks.iter().copied().chain(last).enumerate().map(move |(k, block)| {
        let space = space_bits(&block);
        let starts = !space & (space << 1 | space_before);
        space_before = space >> 63;
        (64 * k, starts)
    })
}

/// The whitespace bytes of a block as bits, bit `i` for `block[i]`.
#[inline(always)]
fn space_bits(block: &[u8; 64]) -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let mut bits = 0;
        for (k, lane) in block.as_chunks::<16>().0.iter().enumerate() {
            // SAFETY: SSE2 is part of every x86_64 target, and the load reads the 16
            // bytes of `lane`, unaligned.
            let mask = unsafe {
                let v = _mm_loadu_si128(lane.as_ptr().cast());
                let eq = |c: u8| _mm_cmpeq_epi8(v, _mm_set1_epi8(c as i8));
                _mm_movemask_epi8(_mm_or_si128(_mm_or_si128(eq(b' '), eq(b'\n')), _mm_or_si128(eq(b'\t'), eq(b'\r'))))
            };
            bits |= u64::from(mask as u16) << (16 * k);
        }
        bits
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        space_bits_scalar(block)
    }
}

/// [`space_bits`] a byte at a time: for other targets, and to check the vector one.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn space_bits_scalar(block: &[u8; 64]) -> u64 {
    block.iter().enumerate().fold(0, |bits, (i, &c)| bits | u64::from(is_space(c)) << i)
}

/// m / 10^k correctly rounded to `f32`, for m ≤ 2²⁴ and k ≤ 7, by one multiplication in
/// `f64` (a division stalled the list loop: a third of its time).
///
/// Why it rounds correctly: the reciprocal and the product each round once in `f64`,
/// so the product is within 2⁻⁵² (relative) of q = m / 10^k. Rounding it to `f32` gives
/// q's nearest float unless q lies closer than that to a midpoint between two floats.
/// It never does: q − M for a midpoint M = (2j + 1)·2^E is a whole multiple of
/// 1 / (5^k·2^L) with L = max(k, −E), so unless it is 0 it is at least 2⁻⁴¹·q (2j + 1 <
/// 2²⁵ and 5⁷ < 2¹⁷), or 2⁻²⁴·q when L = k. And it is never 0: a q that is a dyadic
/// fraction is (m / 5^k)·2⁻ᵏ, of at most 24 significant bits, and a midpoint needs 25.
#[inline(always)]
fn short_quotient(m: u64, k: usize) -> f32 {
    const RECIPROCAL: [f64; 8] = [1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7];
    (m as f64 * RECIPROCAL[k]) as f32
}

/// The decimal digit at `text[i]`, or 10 for anything else (and past the end).
fn digit(text: &[u8], i: usize) -> u8 {
    text.get(i).map_or(10, |c| c.wrapping_sub(b'0').min(10))
}

/// A correctly rounded `f32`, rounded once from the decimal text.
pub fn parse_f32(b: &[u8]) -> Option<f32> {
    match fast_f32(b, 0) {
        Ok((v, _)) => Some(v),
        Err(_) => standard(b),
    }
}

/// The standard library's correctly rounded parse: every form the fast paths decline.
fn standard<T: std::str::FromStr>(b: &[u8]) -> Option<T> {
    std::str::from_utf8(b).ok()?.parse().ok()
}

/// Plain decimals with at most 8 significant digits and 10 fraction digits take
/// Clinger's exact path: the digits (≤ 2²⁴) and the power of ten (≤ 10¹⁰) are both
/// exact in `f32`, so one division rounds correctly. Everything else (exponents, `inf`,
/// more digits, junk) is `Err` with the end of the word, for the standard parser.
fn fast_f32(text: &[u8], at: usize) -> Result<(f32, usize), usize> {
    const POW10: [f32; 11] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];
    let d = Decimal::read(text, at);
    let ends = text.get(d.end).is_none_or(|&c| is_space(c));
    if ends && d.exact(1 << 24, 10) {
        let v = d.mantissa as f32 / POW10[d.fraction];
        return Ok((if d.neg { -v } else { v }, d.end));
    }
    let i = d.end;
    Err(i + text[i..].iter().position(|&c| is_space(c)).unwrap_or(text.len() - i))
}

/// A correctly rounded `f64` (transform and directive operands): Clinger's exact
/// path for plain decimals of at most 2⁵³ in their digits and 22 fraction digits,
/// the standard parser for everything else.
pub fn parse_f64(b: &[u8]) -> Option<f64> {
    const POW10: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19,
        1e20, 1e21, 1e22,
    ];
    let d = Decimal::read(b, 0);
    if d.end == b.len() && d.exact(1 << 53, 22) {
        let v = d.mantissa as f64 / POW10[d.fraction];
        return Some(if d.neg { -v } else { v });
    }
    standard(b)
}

/// The parts of a plain decimal (`-12.5`, `+.5`, `3.`) read from `text[at]` on.
struct Decimal {
    neg: bool,
    /// Its digits as one integer (wrapped if there are more than 19).
    mantissa: u64,
    digits: usize,
    /// How many digits follow the point.
    fraction: usize,
    /// Where the decimal's text ends (at anything that is not part of it).
    end: usize,
}

impl Decimal {
    fn read(text: &[u8], at: usize) -> Decimal {
        let neg = text.get(at) == Some(&b'-');
        let from = at + matches!(text.get(at), Some(b'-' | b'+')) as usize;
        let mut mantissa = 0;
        let mut end = read_digits(text, from, &mut mantissa);
        let (mut digits, mut fraction) = (end - from, 0);
        if text.get(end) == Some(&b'.') {
            let after = read_digits(text, end + 1, &mut mantissa);
            (fraction, end) = (after - end - 1, after);
            digits += fraction;
        }
        Decimal { neg, mantissa, digits, fraction, end }
    }

    /// Whether the digits, at most `max_mantissa`, and 10^`fraction` are exact in the
    /// target type (at most 19 digits cannot have wrapped the mantissa).
    fn exact(&self, max_mantissa: u64, max_fraction: usize) -> bool {
        (1..=19).contains(&self.digits) && self.mantissa <= max_mantissa && self.fraction <= max_fraction
    }
}

/// Reads the decimal digits from `text[i]` on into `mantissa` (wrapping: the caller
/// bounds their count) and returns where they end. Eight bytes at a time where the
/// text has them (SWAR: the digits' run length from a bit mask, their value from three
/// multiplications), then one at a time.
fn read_digits(text: &[u8], mut i: usize, mantissa: &mut u64) -> usize {
    const POW10: [u64; 9] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000, 100_000_000];
    while let Some(&bytes) = text.get(i..).and_then(|t| t.first_chunk::<8>()) {
        let (n, v) = digit_run(u64::from_le_bytes(bytes));
        if n == 0 {
            return i;
        }
        *mantissa = mantissa.wrapping_mul(POW10[n]).wrapping_add(v);
        i += n;
        if n < 8 {
            return i;
        }
    }
    while let d @ 0..=9 = digit(text, i) {
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(d as u64);
        i += 1;
    }
    i
}

/// The run of decimal digits that 8 bytes start with (the first byte the lowest): its
/// length, 0 to 8, and its value. SWAR: the length from a bit mask, the value from
/// three multiplications.
#[inline(always)]
fn digit_run(bytes: u64) -> (usize, u64) {
    const LANES: u64 = 0x0101_0101_0101_0101;
    // Digits become 0..=9 in their bytes; anything else 10 or more.
    let x = bytes ^ (b'0' as u64 * LANES);
    let not_digit = (((x & (0x7f * LANES)) + (0x76 * LANES)) | x) & (0x80 * LANES);
    let n = not_digit.trailing_zeros() / 8;
    (n as usize, digit_value(x, n))
}

/// The value of the decimal digits in the first `n` bytes of `x` (each byte 0..=9, the
/// first digit the lowest byte), `n` ≤ 8.
#[inline(always)]
fn digit_value(x: u64, n: u32) -> u64 {
    // The n digits to the top bytes, zeros below.
    let v = x.checked_shl(64 - 8 * n).unwrap_or(0);
    let v = (v.wrapping_mul(10) + (v >> 8)) & 0x00ff_00ff_00ff_00ff;
    let v = (v.wrapping_mul(100) + (v >> 16)) & 0x0000_ffff_0000_ffff;
    (v.wrapping_mul(10_000) + (v >> 32)) & 0xffff_ffff
}

/// pbrt-v4's strict integer syntax: optional sign, then digits (`None` on overflow).
pub fn parse_int(b: &[u8]) -> Option<i32> {
    scan_int(b, 0).map(|(v, _)| v)
}

fn scan_int(text: &[u8], at: usize) -> Option<(i32, usize)> {
    let neg = text.get(at) == Some(&b'-');
    let from = at + matches!(text.get(at), Some(b'-' | b'+')) as usize;
    let mut v = 0;
    let end = read_digits(text, from, &mut v);
    if end == from || !text.get(end).is_none_or(|&c| is_space(c)) {
        return None;
    }
    if end - from > 18 {
        // Leading zeros, or too large: more digits than `v` holds exactly.
        let digits = &text[from..end];
        let first = digits.iter().position(|&c| c != b'0').unwrap_or(digits.len());
        v = 0;
        if digits.len() - first > 10 || read_digits(digits, first, &mut v) != digits.len() {
            return None;
        }
    }
    let v = if neg { -(v as i64) } else { v as i64 };
    Some((i32::try_from(v).ok()?, end))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_float_path_agrees_with_the_standard_parser() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..200_000 {
            let r = next();
            let digits = (r % 100_000_000) as u32;
            let places = ((r >> 32) % 12) as usize;
            let s = format!("{digits}");
            let text = if places < s.len() {
                format!("{}{}.{}", if r >> 63 == 1 { "-" } else { "" }, &s[..s.len() - places], &s[s.len() - places..])
            } else {
                format!(".{}{s}", "0".repeat(places - s.len()))
            };
            let want = text.parse::<f32>().map(f32::to_bits).ok();
            assert_eq!(parse_f32(text.as_bytes()).map(f32::to_bits), want, "{text}");
        }
        for t in ["5.", ".5", "-0", "+3", "1e3", "16777217", "0.00000000001", "inf", "-nan"] {
            let (Ok(want), Some(got)) = (t.parse::<f32>(), parse_f32(t.as_bytes())) else { panic!("{t}") };
            assert!(got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()), "{t}");
        }
        assert_eq!(parse_f32(b"1.2.3"), None);
        assert_eq!(parse_f32(b"."), None);
    }

    #[test]
    fn fast_double_path_agrees_with_the_standard_parser() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let digits = format!("{}", state % 10u64.pow(1 + (state >> 59) as u32 % 19));
            let cut = (state >> 32) as usize % (digits.len() + 1);
            let text = format!("{}{}.{}", ["", "-"][(state >> 40) as usize % 2], &digits[..cut], &digits[cut..]);
            assert_eq!(
                parse_f64(text.as_bytes()).map(f64::to_bits),
                text.parse::<f64>().ok().map(f64::to_bits),
                "{text}"
            );
        }
        for t in ["9007199254740993", "0.1", "1e22", "-0", "123456789012345678901234", ".0000000000000000000000001"] {
            assert_eq!(parse_f64(t.as_bytes()).map(f64::to_bits), t.parse::<f64>().ok().map(f64::to_bits), "{t}");
        }
        assert_eq!(parse_f64(b"1.2.3"), None);
    }

    #[test]
    fn list_words_read_as_the_standard_parsers_read_them() {
        let floats =
            ["0", "-0.0", "5.", ".5", "-.5", "-", ".", "-.", "1.2.3", "12345678.5", "1234567.1234567", "0.00000001"];
        let more = ["16777216", "16777217", "8388607.5", "-9999999.9", "0.1234567", "7x", "+1.5", "1e3", "00000001.5"];
        let ints = ["0", "7", "1234567", "12345678", "-5", "+5", "0000007", "2147483647", "2147483648", "5.0", "-"];
        for (word, after) in
            floats.iter().chain(&more).flat_map(|w| ["", " ", "\n", "x", "        ", "\t7 7 7 7 "].map(|a| (w, a)))
        {
            let text = format!("{word}{after}");
            let whole = text.split(|c: char| c.is_ascii_whitespace()).next().unwrap_or_default();
            let want = whole.parse::<f32>().ok().map(|v| (v.to_bits(), whole.len()));
            let got = <f32 as ListNumber>::scan(text.as_bytes(), 0).map(|(v, end)| (v.to_bits(), end));
            assert_eq!(got, want, "{text:?}");
        }
        for (word, after) in ints.iter().flat_map(|w| ["", " ", "\r\n", "x", "         "].map(|a| (w, a))) {
            let text = format!("{word}{after}");
            let whole = text.split(|c: char| c.is_ascii_whitespace()).next().unwrap_or_default();
            let want = whole.parse::<i32>().ok().map(|v| (v, whole.len()));
            assert_eq!(<i32 as ListNumber>::scan(text.as_bytes(), 0), want, "{text:?}");
        }
    }

    /// Every place of the point in words of up to 9 bytes, signed or not, followed by
    /// whitespace, junk or nothing: the one-word reader reads what the standard parser
    /// reads, or hands the word on.
    #[test]
    fn one_word_coordinates_read_as_the_standard_parser() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..20 {
            for len in 1..=9 {
                for point in 0..len {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    let mut word: Vec<u8> = (0..len).map(|k| b'0' + (state >> (4 * k)) as u8 % 10).collect();
                    word[point] = b'.';
                    for (sign, after) in [("", ""), ("-", " "), ("", "\n"), ("-", "x"), ("", "."), ("", "5 ")] {
                        let text = format!("{sign}{}{after}", String::from_utf8_lossy(&word));
                        let whole = text.split(|c: char| c.is_ascii_whitespace()).next().unwrap_or_default();
                        let want = whole.parse::<f32>().ok().map(|v| (v.to_bits(), whole.len()));
                        let got = <f32 as ListNumber>::scan(text.as_bytes(), 0).map(|(v, end)| (v.to_bits(), end));
                        assert_eq!(got, want, "{text:?}");
                        if let Some((v, end)) = word_f32(text.as_bytes(), 0) {
                            assert_eq!(Some((v.to_bits(), end)), want, "{text:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn strict_integers() {
        assert_eq!(parse_int(b"-2147483648"), Some(i32::MIN));
        assert_eq!(parse_int(b"2147483647"), Some(i32::MAX));
        assert_eq!(parse_int(b"2147483648"), None);
        assert_eq!(parse_int(b"99999999999999999999"), None);
        assert_eq!(parse_int(b"+7"), Some(7));
        for bad in [&b"5.0"[..], b"", b"-", b"1e3", b"0x10"] {
            assert_eq!(parse_int(bad), None);
        }
    }

    /// Numbers in the forms real files use and the ones that take the slow paths:
    /// short and long digit runs (over 8 and over 19 digits), leading zeros, signs,
    /// exponents.
    fn number_words(n: usize, ints: bool) -> Vec<String> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        (0..n)
            .map(|_| {
                let r = next();
                let digits = format!("{}", r % 10u64.pow(1 + (r >> 60) as u32 % 12));
                let zeros = "0".repeat(((r >> 40) % 4 == 0) as usize * ((r >> 50) % 24) as usize);
                let sign = ["", "-", "+", ""][(r >> 20) as usize % 4];
                match (ints, (r >> 30) % 5) {
                    (true, _) => format!("{sign}{zeros}{digits}"),
                    (false, 0) => format!("{sign}{digits}e-{}", r % 40),
                    (false, 1) => format!("{sign}{zeros}{digits}"),
                    (false, _) => {
                        let cut = (r >> 8) as usize % (digits.len() + 1);
                        format!("{sign}{zeros}{}.{}", &digits[..cut], &digits[cut..])
                    }
                }
            })
            .collect()
    }

    /// The words joined by varied whitespace, past the parallel reader's threshold.
    fn long_list(words: &[String]) -> String {
        let spaces = [" ", "\n", "\t ", "\r\n", "   "];
        let mut text: String = words.iter().enumerate().map(|(k, w)| format!("{w}{}", spaces[k % 5])).collect();
        assert!(text.len() > PARALLEL_LIST_BYTES, "the list must take the parallel path");
        text.push(']');
        text
    }

    #[test]
    fn long_lists_read_in_parallel_match_the_standard_parsers_word_by_word() {
        let floats = number_words(200_000, false);
        let mut values = Values::Floats(Vec::new());
        let text = long_list(&floats);
        assert_eq!(parallel_numbers(text.as_bytes(), &mut values), Some(text.len() - 1));
        let Values::Floats(got) = values else { unreachable!() };
        let want: Vec<u32> = floats.iter().map(|w| w.parse::<f32>().unwrap().to_bits()).collect();
        assert_eq!(got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), want);

        // Integers that fit, and a list whose one word overflows (left to the reader).
        let ints: Vec<String> = number_words(300_000, true).into_iter().filter(|w| w.parse::<i32>().is_ok()).collect();
        let mut values = Values::Ints(vec![7]);
        let text = long_list(&ints);
        assert_eq!(parallel_numbers(text.as_bytes(), &mut values), Some(text.len() - 1));
        let Values::Ints(got) = values else { unreachable!() };
        let want: Vec<i32> = std::iter::once(7).chain(ints.iter().map(|w| w.parse().unwrap())).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn a_word_that_is_not_a_number_leaves_a_long_list_untouched() {
        for (bad, ints) in [("1.5x", false), ("#", false), ("\"a\"", false), ("5.0", true), ("2147483648", true)] {
            let mut words: Vec<String> =
                number_words(250_000, true).into_iter().filter(|w| w.parse::<i32>().is_ok()).collect();
            words[123_456] = bad.to_string();
            let mut values = if ints { Values::Ints(Vec::new()) } else { Values::Floats(Vec::new()) };
            assert_eq!(parallel_numbers(long_list(&words).as_bytes(), &mut values), None, "{bad}");
            assert_eq!(values.len(), 0, "{bad}");
        }
    }

    /// Sampled against the standard parser, with the edges.
    #[test]
    fn short_quotients_round_as_the_standard_parser() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for i in 0..300_000u64 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let m = match i % 3 {
                0 => state % (1 << 24) + 1,
                1 => (1 << 24) - i % 1000,
                _ => i % 100_000,
            };
            check_short_quotient(m, (state >> 40) as usize % 8);
        }
    }

    /// Every case, against an f64 division rounded to f32: both operands are exact in
    /// f64 and a quotient rounded to 53 bits and then to 24 is the quotient rounded to
    /// 24 (double rounding is harmless for division when 53 ≥ 2·24 + 2, Figueroa 1995).
    #[test]
    fn every_short_quotient_rounds_correctly() {
        use rayon::prelude::*;
        const POW10: [f64; 8] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7];
        let wrong = (0..=(1u64 << 24))
            .into_par_iter()
            .flat_map_iter(|m| (0..8).map(move |k| (m, k)))
            .find_any(|&(m, k)| short_quotient(m, k).to_bits() != ((m as f64 / POW10[k]) as f32).to_bits());
        assert_eq!(wrong, None);
    }

    fn check_short_quotient(m: u64, k: usize) {
        let exact = format!("{m}e-{k}");
        let want = exact.parse::<f32>().unwrap();
        assert_eq!(short_quotient(m, k).to_bits(), want.to_bits(), "{exact}");
    }

    #[test]
    fn the_first_close_bracket_is_found_in_any_piece() {
        let n = 5 * PARALLEL_LIST_BYTES + 123;
        let mut text = vec![b'7'; n];
        assert_eq!(find_close(&text), None);
        let edges = [0, 1, PARALLEL_LIST_BYTES - 1, PARALLEL_LIST_BYTES, 3 * PARALLEL_LIST_BYTES - 1, n - 1];
        for &at in edges.iter().rev() {
            text[at] = b']';
            assert_eq!(find_close(&text), Some(at));
        }
    }

    /// Every byte value at every place of a block, among random bytes.
    #[test]
    fn vector_space_masks_are_the_scalar_ones() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for k in 0..64 * 256 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mut block: [u8; 64] = std::array::from_fn(|i| b" \t\r\n7.x]"[(state >> (i % 60)) as usize % 8]);
            block[k % 64] = (k / 64) as u8;
            assert_eq!(space_bits(&block), space_bits_scalar(&block), "{block:?}");
        }
    }

    #[test]
    fn words_are_counted_across_runs_and_edges() {
        for n in [0, 1, 2, 31, 32, 33, 63, 64, 65, 254, 255, 256, 510, 511, 1000] {
            for text in ["7".repeat(n), " ".repeat(n), "7 ".repeat(n), " 7".repeat(n), "77\t".repeat(n)] {
                let want = text.split(|c: char| c.is_ascii_whitespace()).filter(|w| !w.is_empty()).count();
                assert_eq!(count_words(text.as_bytes()), want, "{text:?}");
            }
        }
    }
}
