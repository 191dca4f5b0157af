//! The `bareray` command: see `bareray --help`.

fn main() -> std::process::ExitCode {
    bareray::cli::main()
}
