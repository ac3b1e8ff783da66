"""Scene labels are placed clear of the boxes they name and of each other."""

from rocas.viz.labels import LabelItem, label_anchors, label_extent, label_rects, place_labels


def _overlap(a, b):
    return min(a[2], b[2]) > max(a[0], b[0]) and min(a[3], b[3]) > max(a[1], b[1])


def test_crowded_labels_collide_with_nothing():
    # a queue of cars 5 m apart and a cone between two of them: every label had to move
    items = [LabelItem(f"vehicle #{i}", (5.0 * i, 0.0), 2.5) for i in range(6)]
    items.insert(0, LabelItem("collision with vehicle #2 at 6.85 s", (10.0, 0.0), 4.0))
    items.append(LabelItem("trafficcone #3", (7.5, 1.0), 0.4))
    rects = label_rects(items, place_labels(items))
    boxes = [(it.center[0] - it.radius, it.center[1] - it.radius,
              it.center[0] + it.radius, it.center[1] + it.radius) for it in items]
    for i, r in enumerate(rects):
        assert not any(_overlap(r, b) for b in boxes), items[i].text
        assert not any(_overlap(r, o) for j, o in enumerate(rects) if j != i), items[i].text


def test_the_anchor_sits_above_the_rectangle_centre():
    item = LabelItem("ego", (0.0, 0.0), 2.0)
    (x, y), = label_anchors([item], [(3.0, 4.0)])
    assert x == 3.0 and y == 4.0 - label_extent("ego")[1] / 2  # Rerun draws it below the point
