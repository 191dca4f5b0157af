//! The `bareray` command: see `bareray --help`. This crate holds what only the command needs: argument
//! parsing and printing ([`cli`]), the CPU check ([`cpu`]) and the allocator ([`huge_pages`]); everything
//! else is the `bareray` library, which it calls.

mod cli;
mod cpu;
mod huge_pages;

// Library modules that cli/particle_args.rs names through `crate::` rather than `bareray::`.
use bareray::{io, math, scene};

/// Large arrays (sphere fields, BVH build buffers, images) on huge pages: fewer page faults.
#[global_allocator]
static ALLOCATOR: huge_pages::HugePages = huge_pages::HugePages;

/// The CPU check ([`cpu`]): an ELF constructor, so that it runs before Rust's runtime, whose start-up
/// code LTO compiles with the build's instruction sets like the rest. Priority 90 puts it before
/// the standard library's own constructor (99, which records the arguments).
#[cfg(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")))]
#[used]
#[link_section = ".init_array.00090"]
static CPU_CHECK: extern "C" fn() = cpu_check;

#[cfg(all(target_os = "linux", any(target_arch = "x86", target_arch = "x86_64")))]
extern "C" fn cpu_check() {
    cpu::check_or_exit();
}

fn main() -> std::process::ExitCode {
    huge_pages::choose();
    cli::main()
}
