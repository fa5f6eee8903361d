//! `bsa`: parse the command line, run it, print the error chain, set the exit code.

use clap::Parser;

fn main() {
    let cli = bsa::cli::Cli::parse();
    if let Err(err) = bsa::cli::run(cli) {
        eprintln!("error: {err}");
        for cause in err.chain().skip(1) {
            eprintln!("  caused by: {cause}");
        }
        std::process::exit(1);
    }
}
