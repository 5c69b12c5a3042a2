//! `mech`: the command-line tool. Everything it does is in [`mech::cli`].

fn main() -> std::process::ExitCode {
    mech::cli::main()
}
