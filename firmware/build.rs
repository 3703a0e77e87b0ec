//! The linker finds the one `memory.x` (STM32F405) at the repository root; defmt's linker
//! script only when the build logs.
fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    println!("cargo:rustc-link-search={}", root.display());
    println!("cargo:rerun-if-changed=../memory.x");
    println!("cargo:rerun-if-changed=../tables/reference.bin");
    println!("cargo:rerun-if-changed=../tables/vhb-batch.bin");
    if std::env::var_os("CARGO_FEATURE_DEFMT").is_some() {
        println!("cargo:rustc-link-arg=-Tdefmt.x");
    }
}
