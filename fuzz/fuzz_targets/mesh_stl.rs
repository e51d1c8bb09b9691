#![no_main]
//! `cargo fuzz run mesh_stl`: see `partscene_fuzz::mesh_stl`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::mesh_stl(data);
});
