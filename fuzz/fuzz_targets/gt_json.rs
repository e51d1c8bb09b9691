#![no_main]
//! `cargo fuzz run gt_json`: see `partscene_fuzz::gt_json`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    partscene_fuzz::gt_json(data);
});
