//! Times the synthesis of one material: `cargo run --release -p datasets --example
//! gen_material -- KIND SIZE OUT` (used for the figures under "Measured" in the README).

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        return Err("usage: gen_material KIND SIZE OUT".into());
    }
    let kind = datasets::MaterialKind::from_name(&args[1])?;
    let spec = datasets::MaterialSpec::new(kind, args[2].parse()?);
    let opts = datasets::GenerateOptions { progress: true, ..Default::default() };
    let r = datasets::generate(&spec, std::path::Path::new(&args[3]), &opts)?;
    println!("{} {}²: {} images in {:.2} s", args[1], args[2], r.images_written, r.seconds);
    Ok(())
}
