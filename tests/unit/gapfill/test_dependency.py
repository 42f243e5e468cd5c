import numpy as np

from handdb.gapfill.dependency import interfinger_neighbours, intrafinger_parents
from handdb.hand.skeletons import load_skeleton

# The thesis program's maps, by feature point id (the lead's reading of appendix B).
THESIS_INTERFINGER = {
    **{p: p for p in (0, 1, 2, 19, 20)},
    3: 7, 4: 8, 5: 9, 6: 10, 7: 11, 8: 12, 9: 13, 10: 14,
    11: 15, 12: 16, 13: 17, 14: 18, 15: 11, 16: 12, 17: 13, 18: 14,
}
THESIS_INTRAFINGER = {
    **{p: p for p in (2, 6, 10, 14, 18, 19, 20)},
    0: 1, 1: 2, 3: 4, 4: 5, 5: 6, 7: 8, 8: 9, 9: 10,
    11: 12, 12: 13, 13: 14, 15: 16, 16: 17, 17: 18,
}


def _by_id(skeleton, neighbours):
    ids = np.asarray(skeleton.ids)
    return {int(ids[j]): int(ids[n]) for j, n in enumerate(neighbours)}


def test_interfinger_map_matches_the_thesis(thesis21):
    assert _by_id(thesis21, interfinger_neighbours(thesis21)) == THESIS_INTERFINGER


def test_intrafinger_map_matches_the_thesis(thesis21):
    assert _by_id(thesis21, intrafinger_parents(thesis21)) == THESIS_INTRAFINGER


def test_maps_follow_names_on_other_skeletons():
    dhg = load_skeleton("dhg22")
    inter = interfinger_neighbours(dhg)
    intra = intrafinger_parents(dhg)
    assert dhg.joints[inter[dhg.index("ring_tip")]] == "little_tip"
    assert dhg.joints[inter[dhg.index("little_pip")]] == "ring_pip"
    assert inter[dhg.index("thumb_cmc")] == dhg.index("thumb_cmc")
    assert dhg.joints[intra[dhg.index("thumb_mcp")]] == "thumb_cmc"
    assert intra[dhg.index("thumb_cmc")] == dhg.index("thumb_cmc")
    assert intra[dhg.index("palm")] == dhg.index("palm")
