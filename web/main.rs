//! The viewer-editor in the browser. Build for `wasm32-unknown-unknown` (see README: `web/build.sh`).

#[cfg(target_arch = "wasm32")]
fn main() {
    partscene::web::start();
}

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    eprintln!("partscene-web runs in the browser: build it with web/build.sh (target wasm32-unknown-unknown)");
    std::process::exit(2);
}
