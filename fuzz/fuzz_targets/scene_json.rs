#![no_main]
//! `cargo fuzz run scene_json`: see `partscene_fuzz::scene_json_target`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::scene_json_target(data);
});
