#![no_main]
//! `cargo fuzz run asset_mjcf`: see `partscene_fuzz::asset_mjcf`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::asset_mjcf(data);
});
