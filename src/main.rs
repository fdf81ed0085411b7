//! The `springlab` binary: everything is in the library; see `springlab --help`.

fn main() -> std::process::ExitCode {
    springlab::cli::main()
}
