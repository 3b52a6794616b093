//! somnurbs: the command line; [`somnurbs::cli::main`] parses it and runs the command.

fn main() -> std::process::ExitCode {
    somnurbs::cli::main()
}
