//! `spectral-skin`: the command line ([`spectral_skin::cli`]).

fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(spectral_skin::cli::main(std::env::args_os()))
}
