"""Screenshots of `restir compare` reports for the README's gallery.

    .venv/bin/python benchmarks/gallery.py out/reports/veach-ajar docs/images/gallery_veach-ajar.png [--keys 0]

Opens the report's index.html in headless chromium (Debian's `chromium` and `chromium-driver`,
as the report test uses; `make browser` installs them), waits until its images are decoded, shows
the image of the given key (0: the reference, 1..: the methods; the report's own keys, then `f`
or `d` for a method's last frame or its denoised last frame) and saves the window.
"""
import argparse
import os
import shutil


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("report", help="the report folder (its index.html)")
    ap.add_argument("png", help="the screenshot to write")
    ap.add_argument("--keys", default="0", help="keys sent to the report before the screenshot (default: 0)")
    ap.add_argument("--size", default="1400,1000", help="window width,height in CSS pixels")
    args = ap.parse_args()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.support.ui import WebDriverWait

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", f"--window-size={args.size}",
              "--allow-file-access-from-files", "--hide-scrollbars"):
        opts.add_argument(a)
    driver = webdriver.Chrome(options=opts, service=Service(shutil.which("chromedriver") or "/usr/bin/chromedriver"))
    try:
        driver.get("file://" + os.path.abspath(os.path.join(args.report, "index.html")))
        WebDriverWait(driver, 120).until(lambda d: d.execute_script("return document.body.dataset.ready === '1'"))
        for key in args.keys:
            ActionChains(driver).send_keys(key).perform()
        os.makedirs(os.path.dirname(os.path.abspath(args.png)), exist_ok=True)
        driver.save_screenshot(args.png)
    finally:
        driver.quit()
    print("wrote", args.png)


if __name__ == "__main__":
    main()
