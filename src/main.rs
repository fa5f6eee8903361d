//! `bsa`: parse the command line, run it, print the error chain, set the exit code.

use clap::Parser;

fn main() {
    // Output piped into `head` and the like: end quietly when the reader goes away, as
    // command-line tools do, instead of panicking on the failed write. Rust ignores
    // SIGPIPE by default; this puts the default action back.
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default at start-up, before any
    // thread exists, has no preconditions.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = bsa::cli::Cli::parse();
    if let Err(err) = bsa::cli::run(cli) {
        eprintln!("error: {err}");
        for cause in err.chain().skip(1) {
            eprintln!("  caused by: {cause}");
        }
        // An interrupted solve saved its progress and said how to resume (an interrupted
        // `bsa new` wrote nothing); it still did not finish, so it must not look like
        // success (or like any other failure).
        std::process::exit(if bsa::cli::guard::is_interruption(&err) {
            bsa::cli::guard::EXIT_INTERRUPTED
        } else {
            1
        });
    }
}
