//! The one seam between the editor and the platform it runs on. The app calls [`Platform`]; a
//! front end (the browser's, in `crate::web`) implements it and hands it in through
//! [`super::LaunchOptions`], so the dependency runs one way: front end → app, never back.
//! On the desktop the defaults apply: the window title is eframe's, dropped files have paths,
//! and exports are written to folders.

use std::fmt::Debug;
use std::sync::Arc;
use std::sync::mpsc::Sender;

use eframe::egui;

/// Files dropped onto the app whose bytes arrive later, as (file name, bytes).
pub type DroppedFiles = Vec<Arc<dyn egui::DroppedFile + Send + Sync>>;

/// What the editor needs from its platform beyond eframe.
pub trait Platform: Debug + Send + Sync {
    /// Shows `title` where the platform names the open document (the browser tab).
    fn set_title(&self, _title: &str) {}

    /// Starts reading dropped files whose bytes the platform gives asynchronously; each arrives
    /// on `tx`.
    fn read_dropped(&self, _files: DroppedFiles, _tx: Sender<(String, Vec<u8>)>) {}

    /// Offers `bytes` to the user as a file named `name` (a download).
    fn download(&self, name: &str, _bytes: &[u8]) -> Result<(), String> {
        Err(format!("cannot offer {name} for download on this platform"))
    }
}

/// The desktop: everything through eframe and the file system.
#[derive(Debug, Default)]
pub struct Desktop;

impl Platform for Desktop {}
