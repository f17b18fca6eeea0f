"""`cadsynth report` end to end: a small path-traced dataset with randomised lights, a depth
sensor and grasp labels, verified and reported by the command line; the page opened in a real
browser (headless Chromium, Debian's `chromium`), which must load it without a console message
and decode every image; skipped, saying so, where chromium is not installed."""

import base64
import html.parser
import io
import os
import re
import shutil
import subprocess

import pytest
from PIL import Image

from conftest import CLI

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
SECTIONS = ["run", "verify", "objects", "images", "randomization", "grasps", "gallery"]


@pytest.fixture(scope="module")
def report(recipe_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "dataset"
    env = dict(os.environ, CADSYNTH_CACHE=str(out.parent / "cache"))
    subprocess.run([str(CLI), "generate", str(recipe_file), "-o", str(out), "--quiet"],
                   check=True, env=env, timeout=600)
    done = subprocess.run([str(CLI), "report", str(out), "--verify"], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("PASS: 6 images"), done.stdout
    return out / "report.html"


class Page(html.parser.HTMLParser):
    """The ids, <img> sources and <script>/<link> tags of a page."""

    def __init__(self, text):
        super().__init__()
        self.ids, self.images, self.external = [], [], []
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.append(attrs["id"])
        if tag == "img":
            self.images.append(attrs.get("src", ""))
        if tag in ("script", "link", "iframe") or re.match(r"https?:", attrs.get("href", "")):
            self.external.append(tag)


def test_the_page_holds_every_section_and_its_images_decode(report):
    text = report.read_text()
    page = Page(text)
    for section in SECTIONS:
        assert section in page.ids, section
    assert not page.external, page.external
    # Every plot and gallery frame inline, and each one decodes.
    assert len(page.images) >= 4 + 3, len(page.images)
    for src in page.images:
        kind, data = re.match(r"data:image/(png|jpeg);base64,(.*)", src).groups()
        image = Image.open(io.BytesIO(base64.b64decode(data)))
        image.load()
        assert image.width > 100 and image.height > 50
    assert "PASS" in text
    # The randomised light count and power, as the recipe drew them.
    assert "light.count" in text and "light.*.power" in text
    assert report.stat().st_size < 3e6


def test_chromium_loads_the_page_without_console_messages_and_decodes_every_image(report,
                                                                                  tmp_path):
    if CHROMIUM is None:
        pytest.skip("chromium is not installed (apt install chromium): the browser test "
                    "needs Debian's headless Chromium")
    # A copy with a probe: once loaded, the title counts the images the browser decoded.
    probe = ("<script>window.addEventListener('load', () => { const all = [...document.images];"
             " const bad = all.filter(i => !(i.complete && i.naturalWidth > 0));"
             " document.title = 'images ' + all.length + ' broken ' + bad.length; });</script>")
    page = tmp_path / "report.html"
    page.write_text(report.read_text().replace("</body>", probe + "</body>"))
    noisy = tmp_path / "noisy.html"  # the console check must see a page's messages
    noisy.write_text("<html><body><script>console.error('boom')</script></body></html>")

    def chromium(path, *extra):
        return subprocess.run(
            [CHROMIUM, "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
             "--enable-logging=stderr", "--v=0", "--virtual-time-budget=5000",
             f"--user-data-dir={tmp_path / 'profile'}", *extra, path.as_uri()],
            capture_output=True, text=True, timeout=300)

    def console(run):
        return [line for line in run.stderr.splitlines() if re.search(r":CONSOLE[:(]", line)]

    assert any("boom" in line for line in console(chromium(noisy, "--dump-dom")))
    dom = chromium(page, "--dump-dom")
    assert dom.returncode == 0, dom.stderr
    assert not console(dom), console(dom)
    title = re.search(r"<title>images (\d+) broken (\d+)</title>", dom.stdout)
    assert title, dom.stdout[:500]
    assert int(title.group(1)) >= 7 and int(title.group(2)) == 0, title.group(0)
    for section in SECTIONS:
        assert f'id="{section}"' in dom.stdout, section
    # A screenshot shows the page: plots, not a blank page.
    shot = tmp_path / "shot.png"
    chromium(report, f"--screenshot={shot}", "--window-size=1200,2400")
    image = Image.open(shot).convert("L")
    colours = image.getcolors(maxcolors=1 << 20)
    assert colours is not None and len(colours) > 50, "the screenshot is nearly blank"
