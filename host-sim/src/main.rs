//! `bushing-sim`: run scenes and regenerate reports (see [`bushing_sim::cli`]).

fn main() -> std::process::ExitCode {
    bushing_sim::cli::main()
}
