//! The kernel source a report measured: a SHA-256 over every file under `src/` and the
//! kernel's `Cargo.toml` (its features and release profile shape the step too), so that CI
//! (`.ci/accuracy_source.py`, which computes the same digest) fails once the kernel changes
//! and the report has not been written again.
//!
//! The digest's input, file after file in the order of their paths (relative to the
//! repository, `/`-separated, compared as bytes): the path, a line feed, the length of the
//! contents in decimal, a line feed, the contents with every CR LF turned into LF. So neither
//! where the repository is checked out nor a checkout's line endings change it.

use std::path::Path;

/// The hex SHA-256 of the kernel's source under `root` (the repository).
pub fn kernel_source_hash(root: &Path) -> std::io::Result<String> {
    let mut files = vec!["Cargo.toml".to_string()];
    collect(root, "src", &mut files)?;
    files.sort();
    let mut input = Vec::new();
    for file in &files {
        let bytes = std::fs::read(root.join(file))?;
        let mut text = Vec::with_capacity(bytes.len());
        for (k, &b) in bytes.iter().enumerate() {
            if !(b == b'\r' && bytes.get(k + 1) == Some(&b'\n')) {
                text.push(b);
            }
        }
        input.extend_from_slice(format!("{file}\n{}\n", text.len()).as_bytes());
        input.extend_from_slice(&text);
    }
    Ok(sha256(&input).iter().map(|b| format!("{b:02x}")).collect())
}

/// The files under `root/dir`, as `/`-separated paths relative to `root`.
fn collect(root: &Path, dir: &str, out: &mut Vec<String>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(root.join(dir))? {
        let entry = entry?;
        let name = format!("{dir}/{}", entry.file_name().to_string_lossy());
        if entry.file_type()?.is_dir() {
            collect(root, &name, out)?;
        } else {
            out.push(name);
        }
    }
    Ok(())
}

/// `floor(x^(1/n))` of a `u128`, by bisection (n = 2 or 3).
fn root(x: u128, n: u32) -> u128 {
    let (mut lo, mut hi) = (0u128, 1u128 << (128 / n));
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if mid.checked_pow(n).is_some_and(|p| p <= x) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// SHA-256 (FIPS 180-4). Its constants are the first 32 bits of the fractional parts of the
/// square roots (initial hash) and cube roots (round constants) of the first primes,
/// computed here exactly in integers.
fn sha256(message: &[u8]) -> [u8; 32] {
    let primes: Vec<u128> = (2u128..)
        .filter(|&n| (2..n).take_while(|d| d * d <= n).all(|d| n % d != 0))
        .take(64)
        .collect();
    let mut h: Vec<u32> = primes[..8]
        .iter()
        .map(|&p| root(p << 64, 2) as u32)
        .collect();
    let k: Vec<u32> = primes.iter().map(|&p| root(p << 96, 3) as u32).collect();
    let mut data = message.to_vec();
    data.push(0x80);
    while data.len() % 64 != 56 {
        data.push(0);
    }
    data.extend_from_slice(&(message.len() as u64 * 8).to_be_bytes());
    for block in data.chunks_exact(64) {
        let mut w = [0u32; 64];
        for t in 0..64 {
            w[t] = if t < 16 {
                u32::from_be_bytes(block[4 * t..4 * t + 4].try_into().unwrap())
            } else {
                let s0 = w[t - 15].rotate_right(7) ^ w[t - 15].rotate_right(18) ^ (w[t - 15] >> 3);
                let s1 = w[t - 2].rotate_right(17) ^ w[t - 2].rotate_right(19) ^ (w[t - 2] >> 10);
                w[t - 16]
                    .wrapping_add(s0)
                    .wrapping_add(w[t - 7])
                    .wrapping_add(s1)
            };
        }
        let mut v: [u32; 8] = h[..].try_into().unwrap();
        for t in 0..64 {
            let [a, b, c, d, e, f, g, hh] = v;
            let s1 = e.rotate_right(6) ^ e.rotate_right(11) ^ e.rotate_right(25);
            let ch = (e & f) ^ (!e & g);
            let t1 = hh
                .wrapping_add(s1)
                .wrapping_add(ch)
                .wrapping_add(k[t])
                .wrapping_add(w[t]);
            let s0 = a.rotate_right(2) ^ a.rotate_right(13) ^ a.rotate_right(22);
            let maj = (a & b) ^ (a & c) ^ (b & c);
            let t2 = s0.wrapping_add(maj);
            v = [t1.wrapping_add(t2), a, b, c, d.wrapping_add(t1), e, f, g];
        }
        for (x, y) in h.iter_mut().zip(v) {
            *x = x.wrapping_add(y);
        }
    }
    let mut out = [0u8; 32];
    for (o, x) in out.chunks_exact_mut(4).zip(&h) {
        o.copy_from_slice(&x.to_be_bytes());
    }
    out
}
