//! Links the `pge` command position-dependent on Linux. As a position-independent
//! executable, its 34 k relative relocations (vtables and static tables, mostly of the
//! preview's GPU stack) were applied at every start: the loader wrote each page of them,
//! about 1 ms of a 3 ms `pge --version` and of every `pge run`. Linked at a fixed address
//! the linker applies them once; only the few symbols of the C libraries are left.
fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo::rustc-link-arg-bin=pge=-no-pie");
    }
}
