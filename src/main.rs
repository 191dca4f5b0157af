//! The `bareray` command: see `bareray --help`.

/// Large arrays (sphere fields, BVH build buffers, images) on huge pages: fewer page faults.
#[global_allocator]
static ALLOCATOR: bareray::huge_pages::HugePages = bareray::huge_pages::HugePages;

/// The CPU check (`bareray::cpu`): an ELF constructor, so that it runs before Rust's runtime, whose start-up
/// code LTO compiles with the build's instruction sets like the rest. Priority 90 puts it before
/// the standard library's own constructor (99, which records the arguments).
#[cfg(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")))]
#[used]
#[link_section = ".init_array.00090"]
static CPU_CHECK: extern "C" fn() = cpu_check;

#[cfg(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")))]
extern "C" fn cpu_check() {
    bareray::cpu::check_or_exit();
}

fn main() -> std::process::ExitCode {
    bareray::cli::main()
}
