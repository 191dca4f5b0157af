//! The startup check for portable binaries. `.cargo/config.toml` builds for x86-64-v3 (AVX2, FMA, BMI1/2,
//! LZCNT, MOVBE, F16C), and its `cargo build-native` alias for the build machine's own CPU (AVX-512 where it
//! has it): the binary may use every instruction set it was built for anywhere (the kernels through `wide`;
//! any other code through the compiler's own vectorisation, and with LTO that includes the standard
//! library's start-up code, which runs before `main`). On a CPU without one of them it would die with
//! SIGILL, without a word: a default build on a CPU older than Haswell, a native build on any CPU that lacks
//! one of the build machine's features. In the `bareray` binary [`check_or_exit`] runs as an ELF
//! constructor, before Rust's runtime and clap, and turns that into an error naming what is missing and how
//! to build for this CPU (elsewhere than Linux, [`check`] runs first thing in `cli::main`).
//!
//! Detection reads CPUID (and XCR0, for whether the OS saves the AVX and AVX-512 registers) directly:
//! `is_x86_feature_detected!` answers `true` for any feature the binary was compiled with, without asking
//! the CPU, so it cannot tell. The check is itself compiled with the build's features; it is kept to a few
//! integer operations and libc calls, and runs before Rust's runtime ([`check_or_exit`]).

/// The variable naming features the check treats as missing (comma-separated, such as `avx512f,fma`): lets
/// a test exercise the error path on any machine.
pub(crate) const ASSUME_LACKS_VAR: &str = "BARERAY_ASSUME_CPU_LACKS";

/// Which CPUID output holds a feature's bit.
#[derive(Clone, Copy, Debug)]
enum Reg {
    /// Leaf 1, ECX.
    L1Ecx,
    /// Leaf 7 subleaf 0, EBX.
    L7Ebx,
    /// Leaf 7 subleaf 0, ECX.
    L7Ecx,
    /// Leaf 7 subleaf 0, EDX.
    L7Edx,
    /// Leaf 7 subleaf 1, EAX.
    L71Eax,
    /// Leaf 0x8000_0001, ECX.
    E1Ecx,
}

/// The register state the OS must save for a feature's instructions to be usable.
#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    /// XMM (always saved on x86-64).
    Sse,
    /// XMM and YMM (XCR0 bits 1–2).
    Avx,
    /// XMM, YMM, opmask and ZMM (XCR0 bits 1–2 and 5–7).
    Avx512,
}

/// One x86 feature: its `target_feature` name, whether this build was compiled with it, and where CPUID
/// reports it.
#[derive(Clone, Copy, Debug)]
#[allow(dead_code)] // `reg`, `bit` and `state` are read on x86 only.
struct Feature {
    name: &'static str,
    compiled: bool,
    reg: Reg,
    bit: u32,
    state: State,
}

macro_rules! features {
    ($($name:tt: $reg:ident[$bit:literal] $state:ident,)*) => {
        /// The features the check knows: x86-64-v2 to v4 and the later AVX-512 and AVX extensions, i.e.
        /// everything the compiler may emit unasked under any `target-cpu` (SSE and SSE2 are x86-64's
        /// baseline; instructions reached only through explicit intrinsics, such as RDRAND, are left out).
        const FEATURES: &[Feature] = &[$(Feature {
            name: $name,
            compiled: cfg!(target_feature = $name),
            reg: Reg::$reg,
            bit: $bit,
            state: State::$state,
        }),*];
    };
}

features! {
    "sse3": L1Ecx[0] Sse,
    "pclmulqdq": L1Ecx[1] Sse,
    "ssse3": L1Ecx[9] Sse,
    "fma": L1Ecx[12] Avx,
    "cmpxchg16b": L1Ecx[13] Sse,
    "sse4.1": L1Ecx[19] Sse,
    "sse4.2": L1Ecx[20] Sse,
    "movbe": L1Ecx[22] Sse,
    "popcnt": L1Ecx[23] Sse,
    "aes": L1Ecx[25] Sse,
    "avx": L1Ecx[28] Avx,
    "f16c": L1Ecx[29] Avx,
    "bmi1": L7Ebx[3] Sse,
    "avx2": L7Ebx[5] Avx,
    "bmi2": L7Ebx[8] Sse,
    "avx512f": L7Ebx[16] Avx512,
    "avx512dq": L7Ebx[17] Avx512,
    "adx": L7Ebx[19] Sse,
    "avx512ifma": L7Ebx[21] Avx512,
    "avx512cd": L7Ebx[28] Avx512,
    "sha": L7Ebx[29] Sse,
    "avx512bw": L7Ebx[30] Avx512,
    "avx512vl": L7Ebx[31] Avx512,
    "avx512vbmi": L7Ecx[1] Avx512,
    "avx512vbmi2": L7Ecx[6] Avx512,
    "gfni": L7Ecx[8] Sse,
    "vaes": L7Ecx[9] Avx,
    "vpclmulqdq": L7Ecx[10] Avx,
    "avx512vnni": L7Ecx[11] Avx512,
    "avx512bitalg": L7Ecx[12] Avx512,
    "avx512vpopcntdq": L7Ecx[14] Avx512,
    "avx512fp16": L7Edx[23] Avx512,
    "avxvnni": L71Eax[4] Avx,
    "avx512bf16": L71Eax[5] Avx512,
    "lzcnt": E1Ecx[5] Sse,
}

/// The x86 features this binary was compiled for, among those the check knows (the `target_feature`s
/// enabled by `-C target-cpu=...`), in the order of CPUID's registers and bits. Empty on other architectures.
pub(crate) fn required_features() -> Vec<&'static str> {
    FEATURES.iter().filter(|f| f.compiled).map(|f| f.name).collect()
}

/// The compiled-for features that `has` says the CPU lacks.
#[cfg(test)]
fn missing_features(has: impl Fn(&str) -> bool) -> Vec<&'static str> {
    names(missing_mask(has)).collect()
}

/// [`missing_features`] as bits of [`FEATURES`] (no allocation: the check runs before Rust's runtime).
fn missing_mask(has: impl Fn(&str) -> bool) -> u64 {
    let mut mask = 0;
    for (i, f) in FEATURES.iter().enumerate() {
        if f.compiled && !has(f.name) {
            mask |= 1 << i;
        }
    }
    mask
}

/// The names of the features in `mask`.
fn names(mask: u64) -> impl Iterator<Item = &'static str> {
    FEATURES.iter().enumerate().filter(move |(i, _)| mask & (1 << i) != 0).map(|(_, f)| f.name)
}

/// Whether the comma-separated `list` (an [`ASSUME_LACKS_VAR`] value, such as `avx512f,fma`; blanks
/// around names ignored) names `feature`.
pub(crate) fn lists(list: &[u8], feature: &str) -> bool {
    list.split(|&b| b == b',').any(|name| name.trim_ascii() == feature.as_bytes())
}

/// The error for a CPU that lacks `missing` of the `required` features, in pieces handed to `emit`: what
/// the binary needs, what is missing, why it stops, and how to get a binary that runs here.
fn emit_message<'a>(
    required: impl Iterator<Item = &'a str>,
    missing: impl Iterator<Item = &'a str>,
    mut emit: impl FnMut(&str),
) {
    emit(
        "error: this CPU lacks instructions this bareray binary was compiled for, so it stops here \
         instead of crashing with an illegal instruction.\n  missing:",
    );
    for name in missing {
        emit(" ");
        emit(name);
    }
    emit("\n  required:");
    for name in required {
        emit(" ");
        emit(name);
    }
    emit(
        "\nThe default build, `cargo build --release` (.cargo/config.toml), is for x86-64-v3: AVX2, FMA and \
         BMI2 (Intel Haswell, AMD Zen and later); `cargo build-native` builds for the CPU that runs the build \
         and runs only on CPUs with all of its instruction sets. For a CPU without AVX2 and FMA, build for a \
         lower baseline: RUSTFLAGS=\"-C target-cpu=x86-64-v2\" cargo build --release (SSE4.2; or x86-64 \
         for any x86-64 CPU).\n",
    );
}

/// The message that names the features the CPU lacks and how to build for it, as one string (ending in a
/// newline).
// Called first thing in `cli::main` where the ELF constructor does not run (and by the tests).
#[cfg_attr(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")), allow(dead_code))]
pub(crate) fn message(required: &[&str], missing: &[&str]) -> String {
    let mut out = String::new();
    emit_message(required.iter().copied(), missing.iter().copied(), |s| out.push_str(s));
    out
}

/// The startup check: `Err` with [`message`] when the CPU (or [`ASSUME_LACKS_VAR`]) lacks a feature this
/// binary was compiled for. Always `Ok` on other architectures. Uses the standard library (the environment,
/// a `String`): where that is compiled for the build machine too (LTO), use [`check_or_exit`].
// Called first thing in `cli::main` where the ELF constructor does not run (and by the tests).
#[cfg_attr(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")), allow(dead_code))]
pub(crate) fn check() -> Result<(), String> {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        let assumed = std::env::var(ASSUME_LACKS_VAR).unwrap_or_default();
        let cpu = detect::Cpu::read();
        let missing = missing_mask(|name| cpu.has(name) && !lists(assumed.as_bytes(), name));
        if missing != 0 {
            return Err(message(&required_features(), &names(missing).collect::<Vec<_>>()));
        }
    }
    Ok(())
}

/// The startup check without Rust's runtime, for an ELF constructor that runs before it (the `bareray`
/// binary's, `main.rs`): with LTO the standard library's start-up code is compiled with the build's
/// instruction sets like everything else, so a check in `main` would come too late. Reads the environment
/// with `getenv`, writes [`message`] to stderr with `write` and leaves with `_exit(1)`: libc calls,
/// compiled for any x86-64; no allocation, no formatting.
#[cfg(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")))]
pub(crate) fn check_or_exit() {
    // SAFETY: the name is NUL-terminated; a non-null result is a NUL-terminated string that lives as long
    // as the environment, which nothing changes before `main`.
    let assumed = unsafe {
        let value = libc::getenv(c"BARERAY_ASSUME_CPU_LACKS".as_ptr());
        if value.is_null() {
            &[][..]
        } else {
            std::ffi::CStr::from_ptr(value).to_bytes()
        }
    };
    let cpu = detect::Cpu::read();
    let missing = missing_mask(|name| cpu.has(name) && !lists(assumed, name));
    if missing == 0 {
        return;
    }
    let required = FEATURES.iter().filter(|f| f.compiled).map(|f| f.name);
    emit_message(required, names(missing), |s: &str| {
        let mut bytes = s.as_bytes();
        while !bytes.is_empty() {
            // SAFETY: writes live bytes to stderr.
            let n = unsafe { libc::write(2, bytes.as_ptr().cast(), bytes.len()) };
            if n <= 0 {
                return;
            }
            bytes = &bytes[n as usize..];
        }
    });
    // SAFETY: ends the process at once; nothing of Rust's runtime has started.
    unsafe { libc::_exit(1) }
}

/// The features x86-64-v2 adds to x86-64's baseline (SSE4.2 and what comes with it).
pub(crate) const X86_64_V2: &[&str] = &["sse3", "ssse3", "sse4.1", "sse4.2", "popcnt", "cmpxchg16b"];

/// The features x86-64-v3 adds to x86-64-v2 (AVX2 and FMA, with their companions).
pub(crate) const X86_64_V3: &[&str] = &["avx", "avx2", "fma", "bmi1", "bmi2", "lzcnt", "movbe", "f16c"];

/// The features x86-64-v4 adds to x86-64-v3 (the AVX-512 subsets every AVX-512 CPU has had since Skylake-SP).
pub(crate) const X86_64_V4: &[&str] = &["avx512f", "avx512bw", "avx512cd", "avx512dq", "avx512vl"];

/// Which of `features` this CPU lacks (or [`ASSUME_LACKS_VAR`] names as lacking), whatever this binary was
/// compiled for: for telling which other builds can run here (`bench --isa`). Reads CPUID, not
/// `is_x86_feature_detected!`, which answers `true` for every feature this binary was compiled with. On
/// other architectures every feature is lacking.
pub(crate) fn lacking<'a>(features: &[&'a str]) -> Vec<&'a str> {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        let assumed = std::env::var(ASSUME_LACKS_VAR).unwrap_or_default();
        let cpu = detect::Cpu::read();
        features.iter().copied().filter(|f| !cpu.has(f) || lists(assumed.as_bytes(), f)).collect()
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    features.to_vec()
}

/// What the CPU reports, read once.
#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
pub(crate) mod detect {
    use super::{Reg, State, FEATURES};
    #[cfg(target_arch = "x86")]
    use core::arch::x86::{__cpuid, __cpuid_count};
    #[cfg(target_arch = "x86_64")]
    use core::arch::x86_64::{__cpuid, __cpuid_count};

    /// The CPUID registers that hold the features the check knows, and the register state the OS saves.
    #[derive(Clone, Copy, Debug, Default)]
    pub(crate) struct Cpu {
        l1_ecx: u32,
        l7_ebx: u32,
        l7_ecx: u32,
        l7_edx: u32,
        l71_eax: u32,
        e1_ecx: u32,
        avx_state: bool,
        avx512_state: bool,
    }

    impl Cpu {
        /// Reads CPUID (leaves 1, 7.0, 7.1 and 0x8000_0001, where the CPU has them) and XCR0.
        pub(crate) fn read() -> Cpu {
            let mut cpu = Cpu::default();
            let max_leaf = __cpuid(0).eax;
            if max_leaf >= 1 {
                cpu.l1_ecx = __cpuid(1).ecx;
            }
            if max_leaf >= 7 {
                let l7 = __cpuid_count(7, 0);
                (cpu.l7_ebx, cpu.l7_ecx, cpu.l7_edx) = (l7.ebx, l7.ecx, l7.edx);
                if l7.eax >= 1 {
                    cpu.l71_eax = __cpuid_count(7, 1).eax;
                }
            }
            if __cpuid(0x8000_0000).eax >= 0x8000_0001 {
                cpu.e1_ecx = __cpuid(0x8000_0001).ecx;
            }
            // OSXSAVE: the OS enabled XGETBV and reports in XCR0 which registers it saves on a switch.
            if cpu.l1_ecx & (1 << 27) != 0 {
                let xcr0 = xcr0();
                cpu.avx_state = xcr0 & 0b110 == 0b110;
                cpu.avx512_state = xcr0 & 0b1110_0110 == 0b1110_0110;
            }
            cpu
        }

        /// Whether the CPU has the feature `name` and the OS saves its registers; `false` for names the
        /// check does not know.
        pub(crate) fn has(&self, name: &str) -> bool {
            let Some(f) = FEATURES.iter().find(|f| f.name == name) else { return false };
            let reg = match f.reg {
                Reg::L1Ecx => self.l1_ecx,
                Reg::L7Ebx => self.l7_ebx,
                Reg::L7Ecx => self.l7_ecx,
                Reg::L7Edx => self.l7_edx,
                Reg::L71Eax => self.l71_eax,
                Reg::E1Ecx => self.e1_ecx,
            };
            let state = match f.state {
                State::Sse => true,
                State::Avx => self.avx_state,
                State::Avx512 => self.avx512_state,
            };
            reg & (1 << f.bit) != 0 && state
        }
    }

    /// XCR0, the register state the OS saves; only valid when CPUID reports OSXSAVE.
    fn xcr0() -> u64 {
        let (lo, hi): (u32, u32);
        // SAFETY: XGETBV with ECX = 0 only reads XCR0; the caller checked OSXSAVE, which makes it legal.
        unsafe {
            core::arch::asm!("xgetbv", in("ecx") 0, out("eax") lo, out("edx") hi,
                options(nomem, nostack, preserves_flags));
        }
        (u64::from(hi) << 32) | u64::from(lo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_names_are_unique_and_bits_in_range() {
        for (i, f) in FEATURES.iter().enumerate() {
            assert!(f.bit < 32, "{}", f.name);
            assert!(FEATURES[..i].iter().all(|g| g.name != f.name), "{} twice", f.name);
        }
    }

    #[test]
    fn required_features_follow_the_build() {
        let required = required_features();
        assert_eq!(required.contains(&"avx2"), cfg!(target_feature = "avx2"));
        assert_eq!(required.contains(&"avx512f"), cfg!(target_feature = "avx512f"));
        assert_eq!(required.contains(&"fma"), cfg!(target_feature = "fma"));
        assert!(!required.contains(&"sse2"), "baseline features are not checked");
    }

    #[test]
    fn missing_features_are_the_required_ones_the_cpu_lacks() {
        let required = required_features();
        assert!(missing_features(|_| true).is_empty());
        assert_eq!(missing_features(|_| false), required);
        // A feature the build does not use is never missing.
        assert!(missing_features(|name| name != "no-such-feature").is_empty());
        if let Some(&last) = required.last() {
            assert_eq!(missing_features(|name| name != last), [last]);
        }
    }

    #[test]
    fn assumed_lacking_list_is_parsed() {
        assert!(lists(b"avx512f,fma", "avx512f") && lists(b"avx512f,fma", "fma"));
        assert!(lists(b" avx2 , ,bmi2,", "avx2") && lists(b" avx2 , ,bmi2,", "bmi2"));
        assert!(!lists(b"avx512f", "avx512") && !lists(b"avx512f,fma", "avx2"));
        assert!(!lists(b"", "avx2"));
    }

    #[test]
    fn message_names_both_lists_and_the_fix() {
        let m = message(&["avx2", "avx512f", "fma"], &["avx512f"]);
        assert!(m.starts_with("error: "));
        assert!(m.contains("missing: avx512f\n"));
        assert!(m.ends_with(".\n"));
        assert!(m.contains("required: avx2 avx512f fma\n"));
        assert!(m.contains("`cargo build --release`") && m.contains("x86-64-v3"));
        assert!(m.contains("`cargo build-native`"));
        assert!(m.contains("RUSTFLAGS=\"-C target-cpu=x86-64-v2\" cargo build --release"));
    }

    /// Every level's features are ones the check reads from CPUID, so [`lacking`] can answer for them.
    #[test]
    fn level_features_are_known() {
        for name in X86_64_V2.iter().chain(X86_64_V3).chain(X86_64_V4) {
            assert!(FEATURES.iter().any(|f| f.name == *name), "{name}");
        }
    }

    /// A CPU that runs this build has the levels it was compiled for; [`lacking`] answers from CPUID, not
    /// from the build's features.
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[test]
    fn lacking_reads_the_cpu() {
        if std::env::var_os(ASSUME_LACKS_VAR).is_some() {
            return;
        }
        if cfg!(target_feature = "avx2") {
            assert_eq!(lacking(X86_64_V3), Vec::<&str>::new());
        }
        let cpu = detect::Cpu::read();
        let v4: Vec<&str> = X86_64_V4.iter().copied().filter(|f| !cpu.has(f)).collect();
        assert_eq!(lacking(X86_64_V4), v4);
        assert_eq!(lacking(&["no-such-feature"]), ["no-such-feature"]);
    }

    /// The machine running the tests runs the binary it built: nothing compiled for is missing.
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[test]
    fn this_cpu_has_what_this_build_needs() {
        let cpu = detect::Cpu::read();
        assert_eq!(missing_features(|name| cpu.has(name)), Vec::<&str>::new());
        assert!(!cpu.has("no-such-feature"));
    }
}
