"""docs/asset_pack.md lists every asset of the pack, each with its thumbnail."""

from __future__ import annotations

from pathlib import Path

import pytest

from embodichain_assets import catalog
from embodichain_assets.thumbnails import coco_sheet, slug

DOCS = Path(__file__).resolve().parents[3] / "docs"
PAGE = DOCS / "asset_pack.md"


@pytest.fixture(scope="module")
def page() -> str:
    if not PAGE.is_file():
        pytest.skip("docs/asset_pack.md is not beside this checkout")
    return PAGE.read_text(encoding="utf-8")


@pytest.mark.parametrize("name", [a.name for a in catalog.MESHES] + [catalog.DRAWER])
def test_every_asset_is_listed_with_its_thumbnail(page, name):
    image = f"images/{slug(name)}.png"
    assert f"`{name}`" in page, name
    assert f"]({image})" in page, name
    assert (DOCS / image).is_file(), image


def test_textures_and_overview_images_exist(page):
    for image in ("images/asset_coco_background.png", "images/asset_seed_scene.png"):
        assert f"]({image})" in page
        assert (DOCS / image).is_file()


def test_thumbnail_names_and_contact_sheet():
    assert slug(catalog.DRAWER) == "asset_sliding_box_drawer"
    assert slug(catalog.MUG) == "asset_cup"
    assert coco_sheet(columns=8, tile=64).shape == (4 * 64, 8 * 64, 3)
