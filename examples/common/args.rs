//! The examples' command lines: `--option` words, some followed by a number.

use std::process::exit;

/// The number that follows option `flag` in `args`: finite and at least 0 (above 0 where
/// `positive`); otherwise says so on stderr with `usage` and exits with code 2.
pub fn number(
    args: &mut impl Iterator<Item = String>,
    flag: &str,
    positive: bool,
    usage: &str,
) -> f64 {
    match args.next().and_then(|v| v.parse::<f64>().ok()) {
        Some(v) if v.is_finite() && (v > 0.0 || (v == 0.0 && !positive)) => v,
        _ => {
            let what = if positive {
                "a positive number"
            } else {
                "a number >= 0"
            };
            eprintln!("{flag} needs {what}\n{usage}");
            exit(2)
        }
    }
}

/// Says that `flag` is not an option, with `usage`, and exits with code 2.
pub fn unknown(flag: &str, usage: &str) -> ! {
    eprintln!("unknown option {flag}\n{usage}");
    exit(2)
}
