//! How much memory a large structure may take: a limit the user sets (`--memory-limit`), or a
//! share of what the system has available; checked before large allocations and while a
//! compressed operator grows, so that a problem too large for the machine is refused with a
//! message instead of ending in the out-of-memory killer.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// Fraction of the available memory one large allocation may take when no limit is set.
pub const MEMORY_SHARE: f64 = 0.8;

/// The process's limit in bytes (0: none set).
static LIMIT: AtomicU64 = AtomicU64::new(0);

/// Sets the most the whole process may hold resident, in bytes (`None`: [`MEMORY_SHARE`] of
/// the available memory). A run that would pass it is refused before the allocation that
/// would.
pub fn set_memory_limit(bytes: Option<u64>) {
    LIMIT.store(bytes.unwrap_or(0), Ordering::Relaxed);
}

/// The limit set by [`set_memory_limit`], if any.
pub fn memory_limit() -> Option<u64> {
    Some(LIMIT.load(Ordering::Relaxed)).filter(|&l| l > 0)
}

/// Bytes one large structure may still take: what the limit leaves above the memory the
/// process holds now, or [`MEMORY_SHARE`] of the available memory; `None` when neither is
/// known.
pub fn memory_allowance() -> Option<f64> {
    match memory_limit() {
        Some(limit) => Some(limit.saturating_sub(resident_bytes().unwrap_or(0)) as f64),
        None => available_memory().map(|avail| MEMORY_SHARE * avail as f64),
    }
}

/// Where [`memory_allowance`] comes from, in words: the limit less what the process holds,
/// or the share of the available memory.
pub fn allowance_source() -> String {
    match memory_limit() {
        Some(limit) => format!(
            "--memory-limit {} less the {} this process holds",
            size_text(limit as f64),
            size_text(resident_bytes().unwrap_or(0) as f64)
        ),
        None => match available_memory() {
            Some(avail) => format!(
                "{:.0} % of the {} the system has available",
                100.0 * MEMORY_SHARE,
                size_text(avail as f64)
            ),
            None => "no limit known".into(),
        },
    }
}

/// A size in bytes: digits, optionally with K, M, G or T (powers of 1024; `B` or `iB` may
/// follow), as `--memory-limit` and Python's `memory_limit` take it.
pub fn parse_size(text: &str) -> std::result::Result<u64, String> {
    let t = text.trim();
    let t = t.strip_suffix("iB").or_else(|| t.strip_suffix('B')).unwrap_or(t);
    let (digits, shift) = match t.char_indices().last() {
        Some((k, c)) if c.is_ascii_alphabetic() => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                'T' => 40,
                _ => return Err(format!("'{text}': the unit must be K, M, G or T")),
            };
            (&t[..k], shift)
        }
        _ => (t, 0),
    };
    let value: f64 = digits.trim().parse().map_err(|_| format!("'{text}' is no size in bytes"))?;
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("'{text}': the limit must be at least one byte"));
    }
    Ok(bytes as u64)
}

/// `bytes` in GiB.
pub fn gib(bytes: f64) -> f64 {
    bytes / (1u64 << 30) as f64
}

/// `bytes` in GiB from one GiB on, else in MiB, else in KiB.
pub fn size_text(bytes: f64) -> String {
    const GIB: f64 = (1u64 << 30) as f64;
    if bytes >= GIB {
        format!("{:.2} GiB", bytes / GIB)
    } else if bytes >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", bytes / (1u64 << 20) as f64)
    } else {
        format!("{:.1} KiB", bytes / 1024.0)
    }
}

/// Memory the system reports as available, in bytes (`MemAvailable` of /proc/meminfo), if known.
pub fn available_memory() -> Option<u64> {
    kib_field("/proc/meminfo", "MemAvailable:").map(|kib| kib * 1024)
}

/// Memory the process holds resident now, in bytes (`VmRSS` of /proc/self/status), if known.
pub fn resident_bytes() -> Option<u64> {
    kib_field("/proc/self/status", "VmRSS:").map(|kib| kib * 1024)
}

/// Peak resident set size of this process (`VmHWM` of /proc/self/status), in bytes, if known.
pub fn peak_rss_bytes() -> Option<u64> {
    kib_field("/proc/self/status", "VmHWM:").map(|kib| kib * 1024)
}

/// The number after `key` on its line of the /proc file `path` (a size in KiB there).
fn kib_field(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// [`Error::TooLarge`] (naming `dof` and both sizes) when `bytes` exceed
/// [`memory_allowance`]: checked before a large allocation.
pub fn check_fits(bytes: f64, dof: usize) -> Result<()> {
    if let Some(allowed) = memory_allowance() {
        if bytes > allowed {
            return Err(Error::TooLarge {
                dof,
                needed_gib: gib(bytes),
                available_gib: gib(allowed),
            });
        }
    }
    Ok(())
}
