//! Rebuilds the crate when any file under `static/` changes, is added or is
//! removed: release builds embed that folder (`service::static_files`), and
//! `include_bytes!` alone would not notice a new file.

fn main() {
    println!("cargo:rerun-if-changed=../static");
}
