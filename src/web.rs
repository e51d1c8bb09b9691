//! The editor in the browser (wasm32): start-up on the page's canvas, reading files the user drops
//! (browsers give their bytes asynchronously) and downloading exports.

use std::sync::Arc;
use std::sync::mpsc::Sender;

use wasm_bindgen::JsCast;

use crate::app::platform::DroppedFiles;
use crate::app::{LaunchOptions, PartsceneApp, Platform};

/// The browser as the editor's platform: the tab's title, files read asynchronously, downloads.
#[derive(Debug, Default)]
pub struct Browser;

impl Platform for Browser {
    fn set_title(&self, title: &str) {
        set_title(title);
    }

    fn read_dropped(&self, files: DroppedFiles, tx: Sender<(String, Vec<u8>)>) {
        read_dropped(files, tx);
    }

    fn download(&self, name: &str, bytes: &[u8]) -> Result<(), String> {
        download(name, bytes)
    }
}

/// The id of the canvas in `web/index.html`.
pub const CANVAS_ID: &str = "partscene_canvas";

/// Starts the editor on the page's canvas, on the demo room.
pub fn start() {
    eframe::WebLogger::init(log_level()).ok();
    wasm_bindgen_futures::spawn_local(async {
        let Some(document) = web_sys::window().and_then(|w| w.document()) else {
            web_sys::console::error_1(&"partscene: no document".into());
            return;
        };
        let Some(canvas) = document.get_element_by_id(CANVAS_ID).and_then(|e| e.dyn_into::<web_sys::HtmlCanvasElement>().ok()) else {
            web_sys::console::error_1(&format!("partscene: no <canvas id=\"{CANVAS_ID}\"> on the page").into());
            return;
        };
        // No autosave in the browser (no file system); the demo room opens by default.
        let launch = LaunchOptions { autosave: None, platform: Arc::new(Browser), ..LaunchOptions::default() };
        let result = eframe::WebRunner::new()
            .start(canvas, eframe::WebOptions::default(), Box::new(move |cc| Ok(Box::new(PartsceneApp::new(cc, launch)))))
            .await;
        if let Err(e) = result {
            web_sys::console::error_1(&e);
        }
    });
}

fn log_level() -> log::LevelFilter {
    log::LevelFilter::Warn
}

/// Reads dropped files in the background; each arrives on `tx` as (file name, bytes).
fn read_dropped(files: DroppedFiles, tx: Sender<(String, Vec<u8>)>) {
    for file in files {
        let tx = tx.clone();
        wasm_bindgen_futures::spawn_local(async move {
            let name = file.path().display().to_string();
            match file.bytes_async().await {
                Ok(bytes) => {
                    // The receiver is gone only when the app closed.
                    let _ = tx.send((name, bytes));
                }
                Err(e) => web_sys::console::error_1(&format!("partscene: cannot read {name}: {e}").into()),
            }
        });
    }
}

/// Offers `bytes` as a download named `name`.
fn download(name: &str, bytes: &[u8]) -> Result<(), String> {
    let js_err = |e: wasm_bindgen::JsValue| format!("{e:?}");
    let document = web_sys::window().and_then(|w| w.document()).ok_or("no document")?;
    let parts = js_sys::Array::new();
    parts.push(&js_sys::Uint8Array::from(bytes));
    let options = web_sys::BlobPropertyBag::new();
    options.set_type("application/octet-stream");
    let blob = web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options).map_err(js_err)?;
    let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(js_err)?;
    let anchor: web_sys::HtmlAnchorElement = document.create_element("a").map_err(js_err)?.dyn_into().map_err(|_| "not an anchor")?;
    anchor.set_href(&url);
    anchor.set_download(name);
    anchor.click();
    web_sys::Url::revoke_object_url(&url).map_err(js_err)?;
    Ok(())
}

/// Sets the page title (it names the open scene; the browser test waits for it).
fn set_title(title: &str) {
    if let Some(document) = web_sys::window().and_then(|w| w.document())
        && document.title() != title
    {
        document.set_title(title);
    }
}
