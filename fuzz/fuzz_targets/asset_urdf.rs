#![no_main]
//! `cargo fuzz run asset_urdf`: see `partscene_fuzz::asset_urdf`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::asset_urdf(data);
});
