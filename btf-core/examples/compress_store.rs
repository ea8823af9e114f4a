//! Compresses a whole BTF store with the library alone, for timing without the CLI's
//! dependencies: `cargo run --release -p btf-core --example compress_store -- IN OUT [C]`.
//! Prints the report as JSON (the same keys as `btf compress --json`).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        return Err("usage: compress_store IN OUT [COMPONENTS]".into());
    }
    let store = btf_core::store::BtfStore::open(std::path::Path::new(&args[1]))?;
    let params = btf_core::compress::CompressParams {
        components: args.get(3).map(|c| c.parse()).transpose()?.unwrap_or(16),
        ..Default::default()
    };
    let r = btf_core::compress::compress(&store, std::path::Path::new(&args[2]), params, &|| {})?;
    println!("{}", serde_json::to_string(&r)?);
    Ok(())
}
