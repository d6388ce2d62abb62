//! The `sweep` command line: parse arguments, call the library, map errors to exit codes.

mod cli;

use clap::Parser;

fn main() {
    let cli = match cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => std::process::exit(argument_error(e)),
    };
    let code = match cli::run(cli) {
        Ok(()) => demsweep::error::exit::SUCCESS,
        Err(e) => {
            if !e.told() {
                eprintln!("error: {e}");
            }
            e.code()
        }
    };
    std::process::exit(code);
}

/// Help and version print as clap writes them; a bad argument is one line (clap's message
/// without its usage block), exit 2.
fn argument_error(e: clap::Error) -> i32 {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let _ = e.print();
            return 0;
        }
        // `sweep` alone: the help is the answer, but nothing was done.
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            return 2;
        }
        _ => {}
    }
    let text = e.render().to_string();
    let message: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
        .collect();
    eprintln!("{} (see --help)", message.join(" "));
    2
}
