//! Project automation (the `cargo xtask` pattern). Subcommands are added by the issues that need them.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        None | Some("help") | Some("--help") => {
            println!("cargo xtask <command>\n\ncommands:\n  help    this text");
        }
        Some(other) => {
            eprintln!("error: unknown xtask command `{other}` (try `cargo xtask help`)");
            std::process::exit(2);
        }
    }
}
