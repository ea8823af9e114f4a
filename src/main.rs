//! The `btf` command-line tool: argument parsing, validation, and calls into the libraries.
fn main() {}
