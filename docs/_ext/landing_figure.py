"""The figure of the README and of the docs' landing page, drawn from a run, never by hand.

``docs/_static/critic_weights.png`` is the paper's Figure 2 as adparm draws it (the critic
weights of the paper's instance, its 150 s run). Every docs build draws it again from a fresh run
(Sphinx event ``builder-inited``, before the static files are copied), so the site's copy cannot
be stale; the README shows the file committed in the repository, whose texts (title, legends,
the clipped-transient note with its numbers, axis labels) are stored in the PNG's ``Description``
and compared with a fresh run's by ``tests/test_docs.py``. Run this file to redraw it:
``python docs/_ext/landing_figure.py``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

PATH = Path(__file__).resolve().parent.parent / "_static" / "critic_weights.png"
#: The PNG's text key that holds the figure's texts.
KEY = "Description"


def draw() -> Any:
    """The figure: plot_critic_weights of the paper's instance (150 s)."""
    import adparm
    from adparm.plotting import plot_critic_weights

    result = adparm.simulate(adparm.paper_config(), diagnose=False)
    return plot_critic_weights(result)


def texts(figure: Any) -> str:
    """The figure's texts (titles, axis labels, notes on the panels, legends; not the tick
    labels), one a line: what a reader can check against the run."""
    found = [t.get_text() for t in figure.texts]
    for axes in figure.axes:
        found += [axes.get_title(loc=loc) for loc in ("left", "center", "right")]
        found += [axes.get_xlabel(), axes.get_ylabel()]
        found += [t.get_text() for t in axes.texts]
        legend = axes.get_legend()
        if legend is not None:
            found += [legend.get_title().get_text()] + [t.get_text() for t in legend.get_texts()]
    return "\n".join(" ".join(t.split()) for t in found if t.strip())


def write(path: Path = PATH) -> Path:
    """Draws the figure and writes it to ``path`` (PNG, 110 dpi, the texts in its metadata)."""
    figure = draw()
    figure.savefig(path, dpi=110, metadata={KEY: texts(figure), "Software": None})
    return path


def stored_texts(path: Path = PATH) -> str | None:
    """The texts stored in the PNG at ``path`` (None if it has none)."""
    from PIL import Image

    with Image.open(path) as image:
        return image.text.get(KEY)


def _builder_inited(app: Any) -> None:
    write()


def setup(app: Any) -> dict[str, Any]:
    app.connect("builder-inited", _builder_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}


if __name__ == "__main__":
    print(f"wrote {write()}")
