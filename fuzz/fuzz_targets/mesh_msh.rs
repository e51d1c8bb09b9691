#![no_main]
//! `cargo fuzz run mesh_msh`: see `partscene_fuzz::mesh_msh`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::mesh_msh(data);
});
