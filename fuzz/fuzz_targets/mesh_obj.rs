#![no_main]
//! `cargo fuzz run mesh_obj`: see `partscene_fuzz::mesh_obj`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::mesh_obj(data);
});
