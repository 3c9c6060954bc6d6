//! The `ctcal` command line: parses arguments, calls the library, presents results.
//! Exit codes: 0 ok, 2 bad input or usage, 1 internal error.

mod cli;

fn main() {
    std::process::exit(cli::run());
}
