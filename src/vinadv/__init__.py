"""vinadv: adversarial maps for learned path planners (see README.md and the docs).

`vinadv.open(url)` opens a database's results as pandas DataFrames (`vinadv.analysis`); that module is imported on
first use, so `import vinadv` stays light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from vinadv.analysis import Results

__version__ = "0.1.0"


# named as the builtin it shadows here only (nothing in this module opens a file): `vinadv.open(url)`
def open(url: str | None = None) -> Results:
    """Open the vinadv database at `url` for reading, as `vinadv.analysis.Results` (`vinadv.analysis.open`)."""
    # the package's one upward import (the layering test allows it), made when called: pandas, pyarrow and the store
    # load then, not with `import vinadv`
    from vinadv.analysis import open as open_results  # noqa: PLC0415

    return open_results(url)
