"""Drawing vinadv's maps, pairs, value maps and k curves, in one palette (`vinadv.plot.palette.PALETTE`).

    import vinadv.plot

    with vinadv.open("results.db") as results:
        pairs = results.pairs()
    vinadv.plot.pair(pairs.iloc[0])          # a row of the DataFrame
    vinadv.plot.pair("x.pairs.npz", 3)       # pair 3 of a pairs file
    vinadv.plot.k_curve(results.robustness())

The names below are imported from their modules when first used: `vinadv.plot.palette` needs no matplotlib (the
viewer's pages and the report's captions read it), the drawing modules import it at their top
(`thumbnails` draws pixels without it).
"""

from vinadv import lazy_names

#: the package's public names, by the module that defines them
_MODULES = {
    "palette": ("PALETTE", "Palette", "Style"),
    "maps": ("Pair", "as_pair", "draw_map", "draw_map_markers", "draw_pair", "map", "map_legend", "pair", "value_map"),
    "curves": ("WORST_CASE", "draw_k_curve", "k_curve", "k_series"),
    "files": ("figure_format", "save_figure", "svg_text"),
    "thumbnails": ("THUMBNAIL_PIXELS", "thumbnail_images", "thumbnail_scale"),
}
__all__, __getattr__, __dir__ = lazy_names(__name__, _MODULES)
