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
        // An interrupted solve saved its progress and said how to resume; it still did
        // not finish, so it must not look like success (or like any other failure).
        let interrupted = err.downcast_ref::<bsa::cli::guard::Interrupted>().is_some();
        std::process::exit(if interrupted {
            bsa::cli::guard::EXIT_INTERRUPTED
        } else {
            1
        });
    }
}
