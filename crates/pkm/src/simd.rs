//! Which vector instructions the kernels use: one level for the whole process,
//! detected once from the CPU and lowered (never raised) by the environment variable
//! `PKM_SIMD`.
//!
//! Every kernel that has lanes asks [`level`] and takes the widest path it has at or
//! below it; every path has a scalar fallback, and the test suite runs on each level the
//! host has (`PKM_SIMD=scalar` and `PKM_SIMD=avx2` beside the best one). What a level
//! changes in the results is stated by each kernel: most give the same bits on every
//! level; the hexapod's strut lengths differ in the last units of their place where a
//! square root comes from a refined estimate (within 1e-15 relative, tested).
//!
//! ```
//! use pkm::simd::{level, Level};
//! // Whatever the CPU, the scalar path is always there.
//! assert!(level() >= Level::Scalar);
//! assert_eq!("avx2".parse::<Level>(), Ok(Level::Avx2));
//! ```

use std::sync::OnceLock;

/// A set of vector instructions, ordered from none to the widest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Level {
    /// No lane kernels: every pose by the portable per-pose code (still with fused
    /// multiply-adds where the CPU has them, which change no bit).
    Scalar,
    /// x86-64 AVX2 with FMA (x86-64-v3: most laptops and servers since 2013-2015).
    Avx2,
    /// x86-64 AVX-512F (x86-64-v4).
    Avx512,
}

impl Level {
    /// Every level, narrowest first.
    pub const ALL: [Level; 3] = [Level::Scalar, Level::Avx2, Level::Avx512];

    /// The widest level this CPU has.
    pub fn detected() -> Level {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Level::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Level::Avx2;
            }
        }
        Level::Scalar
    }

    /// The name `PKM_SIMD` takes: `scalar`, `avx2`, `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            Level::Scalar => "scalar",
            Level::Avx2 => "avx2",
            Level::Avx512 => "avx512",
        }
    }
}

impl std::fmt::Display for Level {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Level {
    type Err = String;

    fn from_str(s: &str) -> Result<Level, String> {
        Level::ALL
            .into_iter()
            .find(|l| l.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| format!("`{s}` is not a SIMD level: expected scalar, avx2 or avx512"))
    }
}

/// The level the kernels use: [`Level::detected`], or `PKM_SIMD` when it names a level
/// at or below it (a level the CPU lacks is not taken, nor a word that names no level:
/// the detected one is, and [`environment_note`] says why). Read once per process.
pub fn level() -> Level {
    static LEVEL: OnceLock<Level> = OnceLock::new();
    *LEVEL.get_or_init(|| chosen(std::env::var("PKM_SIMD").ok().as_deref(), Level::detected()).0)
}

/// Why `PKM_SIMD` was not followed, for a front end to print: `None` when it is unset,
/// `best`, or a level the CPU has.
pub fn environment_note() -> Option<String> {
    chosen(std::env::var("PKM_SIMD").ok().as_deref(), Level::detected()).1
}

/// The level for `PKM_SIMD`'s word `v` on a CPU whose widest level is `cpu`, and why
/// it is not `v`'s.
fn chosen(v: Option<&str>, cpu: Level) -> (Level, Option<String>) {
    let Some(v) = v
        .map(str::trim)
        .filter(|v| !v.is_empty() && !v.eq_ignore_ascii_case("best"))
    else {
        return (cpu, None);
    };
    match v.parse::<Level>() {
        Ok(l) if l <= cpu => (l, None),
        Ok(l) => (
            cpu,
            Some(format!(
                "PKM_SIMD={l}, but this CPU has {cpu} at most: {cpu} is used"
            )),
        ),
        Err(e) => (cpu, Some(format!("PKM_SIMD: {e}; {cpu} is used"))),
    }
}

#[cfg(test)]
mod tests {
    use super::{chosen, Level};

    #[test]
    fn the_environment_lowers_the_level_and_never_raises_it() {
        let c = |v, cpu| chosen(Some(v), cpu);
        assert_eq!(c("scalar", Level::Avx512), (Level::Scalar, None));
        assert_eq!(c(" AVX2", Level::Avx512), (Level::Avx2, None));
        assert_eq!(c("best", Level::Avx2), (Level::Avx2, None));
        assert_eq!(chosen(None, Level::Avx2), (Level::Avx2, None));
        let (l, note) = c("avx512", Level::Avx2);
        assert_eq!(l, Level::Avx2);
        assert!(note.unwrap().contains("avx2 at most"));
        let (l, note) = c("sse9", Level::Avx2);
        assert_eq!(l, Level::Avx2);
        assert!(note.unwrap().contains("expected scalar, avx2 or avx512"));
        assert!(Level::Scalar < Level::Avx2 && Level::Avx2 < Level::Avx512);
        for l in Level::ALL {
            assert_eq!(l.name().parse::<Level>(), Ok(l));
        }
    }
}
