"""vinadv: adversarial maps for learned path planners (see README.md and the docs).

`vinadv.open(url)` opens a database's results as pandas DataFrames (`vinadv.analysis`); it is imported on first use,
so `import vinadv` stays light.
"""

__version__ = "0.1.0"


def __getattr__(name: str):
    # the package's one upward import, made lazily (the layering test allows it): `vinadv.open` is the analysis entry
    if name == "open":
        from vinadv.analysis import open

        return open
    raise AttributeError(f"module 'vinadv' has no attribute {name!r}")
