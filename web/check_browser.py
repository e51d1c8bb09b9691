#!/usr/bin/env python3
"""Serves web/dist on localhost, opens it in headless Chromium through Playwright, and checks that
the editor starts, opens the demo room and draws it: the page title names the scene, the
screenshot is not blank (many colours in the 3D view), and the console has no errors.

Usage: check_browser.py DIST_DIR [--screenshot OUT.png] [--timeout SECONDS]
Needs: playwright and pillow (pip), and a Chromium (Debian package `chromium`).
"""

import argparse
import functools
import http.server
import io
import shutil
import sys
import threading
import time


class Handler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map, ".wasm": "application/wasm", ".js": "text/javascript"}

    def log_message(self, *args):
        pass


def serve(directory):
    handler = functools.partial(Handler, directory=directory)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dist")
    ap.add_argument("--screenshot")
    ap.add_argument("--timeout", type=float, default=180.0)
    args = ap.parse_args()

    from playwright.sync_api import sync_playwright
    from PIL import Image

    chromium = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if chromium is None:
        sys.exit("check_browser: no Chromium found (apt-get install chromium)")
    server = serve(args.dist)
    url = f"http://127.0.0.1:{server.server_address[1]}/index.html"
    errors = []
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=chromium,
            headless=True,
            args=["--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"],
        )
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        page.on("console", lambda m: errors.append(f"console.{m.type}: {m.text}") if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
        started = time.time()
        page.goto(url)
        # The app sets the title when the demo room is open (generated, scanned, reconstructed in wasm).
        title = ""
        while time.time() - started < args.timeout:
            title = page.title()
            if "demo room" in title or errors:
                break
            time.sleep(0.5)
        # A few frames to draw the scene.
        time.sleep(2.0)
        shot = page.screenshot()
        browser.close()
    server.shutdown()
    elapsed = time.time() - started
    image = Image.open(io.BytesIO(shot)).convert("RGB")
    if args.screenshot:
        image.save(args.screenshot)
    w, h = image.size
    # The 3D view is the middle of the window: count its distinct colours.
    view = image.crop((w // 4, h // 8, 3 * w // 4, 3 * h // 4))
    colours = len(set(view.get_flattened_data() if hasattr(view, "get_flattened_data") else view.getdata()))
    print(f"check_browser: {url}: title {title!r} after {elapsed:.1f} s, {colours} colours in the 3D view, "
          f"{len(errors)} console errors")
    problems = []
    if "demo room" not in title:
        problems.append(f"the demo room did not open within {args.timeout:.0f} s (title {title!r})")
    if colours < 200:
        problems.append(f"the screenshot looks blank ({colours} colours in the 3D view)")
    problems += errors
    if problems:
        sys.exit("check_browser: FAILED:\n  " + "\n  ".join(problems))
    print("check_browser: ok")


if __name__ == "__main__":
    main()
