//! The `bareray` command: see `bareray --help`.

/// Large arrays (sphere fields, BVH build buffers, images) on huge pages: fewer page faults.
#[global_allocator]
static ALLOCATOR: bareray::huge_pages::HugePages = bareray::huge_pages::HugePages;

fn main() -> std::process::ExitCode {
    bareray::cli::main()
}
