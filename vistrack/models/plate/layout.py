"""License-plate layouts and geometry (thesis 001, §1.3.2, Table 1.1, Fig. 1.5).

A plate is a parallelogram with two vertical sides and a fixed aspect ratio:
centre ``(u, w)``, width ``s`` (px; the scale) and the angle ``θ`` of its
non-vertical sides. A point ``(a, b)`` of the unit plate square (``a`` across,
``b`` down) lies at

    x = u + (a - 1/2) s,    y = w + (b - 1/2) s / aspect + (a - 1/2) s tan θ.

A layout lists, in unit-square coordinates, the rectangles of the six pixel
sets of Table 1.1:

- ``h_edge``: bands across the top and bottom borders, where horizontal edges
  are expected;
- ``h_free``: horizontal stripes free of edges and lines (margins and the gap
  between the character rows);
- ``v_edge``: bands across the left and right borders (vertical edges);
- ``v_free``: vertical stripes free of edges and lines;
- ``small``: the small characters; ``big``: the large characters.

A layout may add ``extra`` pixel sets ``(name, rectangles, channel, term)``, each a
mean of one feature map (``0`` |∇_x I|, ``1`` |∇_y I|, ``2`` the small DoG,
``3`` the large DoG) that enters ``r^h``, ``r^v`` or ``r^c`` (``term`` "h", "v",
"c") with a learnt coefficient: the two character areas apart, the Sobel maps
over the characters, edges of the wrong orientation in the border bands, and
bands just outside the plate (the thesis's "could be further refined", §1.3.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PlateLayout", "LAYOUTS", "plate_points", "plate_vertices"]


@dataclass(frozen=True)
class PlateLayout:
    """A plate layout: aspect ratio and the Table 1.1 pixel sets in unit-square coordinates
    (module docstring).

    Attributes
    ----------
    name : str
    aspect : float
        Width / height.
    h_edge, h_free, v_edge, v_free, small, big : tuple of (a0, b0, a1, b1)
        Rectangles of the six pixel sets of Table 1.1.
    extra : tuple of (name, rectangles, channel, term)
        Further pixel sets with learnt coefficients.
    """

    name: str
    aspect: float  # width / height
    h_edge: tuple
    h_free: tuple
    v_edge: tuple
    v_free: tuple
    small: tuple
    big: tuple
    extra: tuple = ()

    def sets(self):
        """The six Table 1.1 pixel sets as ``{name: (R, 4) array of rectangles}``."""
        return {k: np.array(getattr(self, k), float) for k in ("h_edge", "h_free", "v_edge", "v_free", "small", "big")}


#: Japanese plate (Fig. 1.5): white, bordered; a top row of small characters,
#: a small glyph at the left and four large digits below.
#: The edge bands are centred 0.02 inside the outline, on the inner side of the
#: dark border line where the strongest edges are; the only edge-free
#: horizontal stripe is the gap between the rows (stripes in the margins lie
#: within the large DoG's reach of the border and pulled the scale ~10 % small).
JP = PlateLayout(
    name="jp",
    aspect=2.0,
    h_edge=((0.08, -0.04, 0.92, 0.08), (0.08, 0.92, 0.92, 1.04)),
    h_free=((0.06, 0.44, 0.94, 0.49),),
    v_edge=((-0.02, 0.1, 0.06, 0.9), (0.94, 0.1, 1.02, 0.9)),
    v_free=((0.03, 0.15, 0.07, 0.85), (0.93, 0.15, 0.97, 0.85), (0.18, 0.52, 0.22, 0.88)),
    small=((0.28, 0.15, 0.72, 0.41), (0.08, 0.55, 0.17, 0.85)),
    big=((0.24, 0.51, 0.92, 0.89),),
    extra=(
        ("top_s", ((0.28, 0.15, 0.72, 0.41),), 2, "c"), ("top_l", ((0.28, 0.15, 0.72, 0.41),), 3, "c"),
        ("glyph_s", ((0.08, 0.55, 0.17, 0.85),), 2, "c"), ("glyph_l", ((0.08, 0.55, 0.17, 0.85),), 3, "c"),
        ("above_s", ((0.1, -0.45, 0.9, -0.15),), 2, "c"), ("above_l", ((0.1, -0.45, 0.9, -0.15),), 3, "c"),
        ("below_s", ((0.1, 1.15, 0.9, 1.45),), 2, "c"), ("below_l", ((0.1, 1.15, 0.9, 1.45),), 3, "c"),
        ("sides_s", ((-0.3, 0.1, -0.08, 0.9), (1.08, 0.1, 1.3, 0.9)), 2, "c"),
        ("sides_l", ((-0.3, 0.1, -0.08, 0.9), (1.08, 0.1, 1.3, 0.9)), 3, "c"),
        ("big_gx", ((0.24, 0.51, 0.92, 0.89),), 0, "c"), ("big_gy", ((0.24, 0.51, 0.92, 0.89),), 1, "c"),
        ("top_gx", ((0.28, 0.15, 0.72, 0.41),), 0, "c"),
        ("h_edge_gx", ((0.08, -0.04, 0.92, 0.08), (0.08, 0.92, 0.92, 1.04)), 0, "h"),
        ("v_edge_gy", ((-0.02, 0.1, 0.06, 0.9), (0.94, 0.1, 1.02, 0.9)), 1, "v"),
    ),
)

#: single-row plate (European / Indian style): one row of characters, aspect ~4.7
SINGLE_ROW = PlateLayout(
    name="single-row",
    aspect=4.7,
    h_edge=((0.05, -0.1, 0.95, 0.1), (0.05, 0.9, 0.95, 1.1)),
    h_free=((0.04, 0.1, 0.96, 0.17), (0.04, 0.84, 0.96, 0.9)),
    v_edge=((-0.02, 0.12, 0.02, 0.88), (0.98, 0.12, 1.02, 0.88)),
    v_free=((0.015, 0.2, 0.04, 0.8), (0.96, 0.2, 0.985, 0.8)),
    small=((0.06, 0.22, 0.12, 0.78),),
    big=((0.14, 0.2, 0.94, 0.8),),
)

LAYOUTS = {"jp": JP, "single-row": SINGLE_ROW}


def plate_points(pose, ab, aspect):
    """Image points of unit-square points ``ab (..., 2)`` for poses ``(N, 4) = (u, w, θ, s)``.

    Returns ``(N, ...) + (2,)``.
    """
    pose = np.atleast_2d(pose)
    u, w, th, s = (pose[:, k].reshape((-1,) + (1,) * (np.ndim(ab) - 1)) for k in range(4))
    a, b = ab[..., 0][None], ab[..., 1][None]
    x = u + (a - 0.5) * s
    y = w + (b - 0.5) * s / aspect + (a - 0.5) * s * np.tan(th)
    return np.stack([x, y], axis=-1)


def plate_vertices(pose, aspect):
    """The four vertices (top-left, top-right, bottom-right, bottom-left): ``(N, 4, 2)``."""
    return plate_points(pose, np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), aspect)
