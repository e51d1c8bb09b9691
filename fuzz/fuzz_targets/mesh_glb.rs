#![no_main]
//! `cargo fuzz run mesh_glb`: see `partscene_fuzz::mesh_glb`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::mesh_glb(data);
});
