"""The planners vinadv knows by name, one declaration each: its loader as `"module:function"`, its shipped weights
(the model zoo: file, sha256, map size, movement model, licence) and the old spellings of its names.

Names are spelled with hyphens; the old spellings (`vin_robust`, and the zoo's `vin28_robust`,
`vin_mpd32`, `gppn_mpd32`, `neural_astar_mazes32`, `neural_astar_mpd5`) are aliases, accepted wherever a planner
or weights are named, so stored runs, bench chunks and committed entries read and resume unchanged.
"""

from __future__ import annotations

from vinadv.planners.registry.base import PlannerParam, register
from vinadv.planners.registry.models import Model

LOADERS = "vinadv.planners.registry.loaders"
OURS = "MIT (vinadv's own licence: trained by the vinadv authors)"


def ours(*, stem: str, **fields) -> Model:
    """Weights trained by vinadv: the file `stem.pt` under vinadv's licence, with its training record `stem.json`
    and its measured figures `stem.metrics.json` beside it (`metrics=None` where there are none); `fields`: the
    `Model`'s others."""
    return Model(
        **{"file": f"{stem}.pt", "licence": OURS, "record": f"{stem}.json", "metrics": f"{stem}.metrics.json", **fields}
    )


register(
    "vin",
    description="Value Iteration Network (Tamar et al. 2016) with vinadv's exact planning engine (default)",
    entry_point=f"{LOADERS}:load_vin",
    default_file="vin{size}.pt",
    takes_weights=True,
    kind="vin",
    models=(
        ours(
            name="vin28",
            stem="vin28",
            sha256="3138c5fb0583c0c813f3426c2c513dfa9e5c7258d148948d05830fc99a440582",
            size=28,
            moves="octile",
            description="the VIN trained on 28x28 maps: the default planner's weights",
        ),
        ours(
            name="vin64",
            stem="vin64",
            sha256="798e7cd0cc70670fe15695aa74f39c3ea9326521740824d3f06a0bedd728457c",
            size=64,
            moves="octile",
            description="the VIN for 64x64 maps (k = 100): vin28_robust.pt fine-tuned on 64x64 maps",
        ),
    ),
)
register(
    "vin-robust",  # the VIN with its own weights: `--planner vin --weights vin28-robust` is this planner
    description="the VIN, trained from the shift start and adversarially (`vin train --vi-init shift --adversarial`)",
    entry_point=f"{LOADERS}:load_vin",
    kwargs={"name": "vin-robust"},
    default_file="vin{size}_robust.pt",
    kind="vin",
    aliases=("vin_robust",),
    recorded_as="vin_robust",
    models=(
        ours(
            name="vin28-robust",
            stem="vin28_robust",
            sha256="86af3ea83e65f30a0477bab46e98bffaff4231c3f3a5bfcea630c2f4a7e4c97c",
            size=28,
            moves="octile",
            description="the VIN trained from the shift start and adversarially on 28x28 maps",
            aliases=("vin28_robust",),
        ),
    ),
)
register(
    "gppn",
    description="Gated Path Planning Network (Lee et al. 2018): LSTM-gated propagation, the actions of its moves",
    entry_point=f"{LOADERS}:load_gppn",
    default_file="gppn{size}.pt",
    takes_weights=True,
    kind="gppn",
    models=(
        ours(
            name="gppn28",
            stem="gppn28",
            sha256="f8e2dc1ac19e943b9e9da68bd620bd1cf5e9bd8f0967df02fe944f2bc83a0e3d",
            size=28,
            moves="octile",
            description="the GPPN trained on 28x28 maps",
        ),
    ),
)
register(
    "vin-mpd32",  # fixed weights, as vin-robust: another file is planner 'vin' with --weights
    description="the VIN trained on the MP dataset's 32x32 moore maps (six families; docs/guide/mpd.md)",
    entry_point=f"{LOADERS}:load_vin",
    kwargs={"name": "vin-mpd32"},
    default_file="vin_mpd32.pt",
    kind="vin",
    models=(
        ours(
            name="vin-mpd32",
            stem="vin_mpd32",
            sha256="2f06f7552a0e64312f1aa358a86cf8316473bbe1c4097c5bb4565af12c196128",
            size=32,
            moves="moore",
            description="the VIN trained on the MP dataset's six 32x32 families (moore moves)",
            aliases=("vin_mpd32",),
        ),
    ),
)
register(
    "gppn-mpd32",
    description="the GPPN trained on the MP dataset's 32x32 moore maps (six families; docs/guide/mpd.md)",
    entry_point=f"{LOADERS}:load_gppn",
    kwargs={"name": "gppn-mpd32"},
    default_file="gppn_mpd32.pt",
    kind="gppn",
    models=(
        ours(
            name="gppn-mpd32",
            stem="gppn_mpd32",
            sha256="73a3af2f161ca3cbcc828c68137e093defc593f3bdc55acfac6741db779a6983",
            size=32,
            moves="moore",
            description="the GPPN trained on the MP dataset's six 32x32 families (moore moves)",
            aliases=("gppn_mpd32",),
        ),
    ),
)
register(
    "optimal",
    description="exact shortest paths (Dijkstra, lowest action index on ties): the control",
    entry_point=f"{LOADERS}:load_optimal",
)
register(
    "astar",
    description="A* search on the maps' moves, with its expansions (on moore maps the Neural A* authors' vanilla A*)",
    entry_point=f"{LOADERS}:load_astar",
)
register(
    "wastar",
    description="weighted A* search, f = g + w*h: fewer expansions, suboptimal paths (wastar:w=3)",
    entry_point=f"{LOADERS}:load_wastar",
    params=(PlannerParam("w", 2.0, "the weight of the heuristic (1: A*)", minimum=1.0),),
)
register(
    "neural-astar",
    description="Neural A* (Yonetani et al. 2021): a CNN's guidance costs searched by A*, on moore maps",
    entry_point=f"{LOADERS}:load_neural_astar",
    default_file="neural_astar_mazes32.pt",  # one model for every size: the encoder is fully convolutional
    takes_weights=True,
    kind="neural-astar",
    models=(
        Model(
            name="neural-astar-mazes32",
            file="neural_astar_mazes32.pt",
            sha256="04d61e5441975a924713b98ee1cd8c00cd881d1afa7740ee946a27f6aca7c006",
            size=None,
            moves="moore",
            description="Neural A*'s encoder, converted from the authors' mazes_032_moore_c8 checkpoint (any map size)",
            licence="MIT, Copyright (c) 2021 OMRON SINIC X Corporation (the Neural A* authors)",
            record="neural_astar_mazes32.json",
            licence_file="neural_astar_mazes32.LICENSE.txt",
            aliases=("neural_astar_mazes32",),
        ),
    ),
)
register(
    "neural-astar-mpd5",  # its own weights: other weights are planner 'neural-astar' with weights
    description="Neural A* trained by `vinadv neural-astar train` on the five MP families other than mazes",
    entry_point=f"{LOADERS}:load_neural_astar",
    kwargs={"name": "neural-astar-mpd5"},
    default_file="neural_astar_mpd5.pt",
    kind="neural-astar",
    models=(
        ours(
            name="neural-astar-mpd5",
            stem="neural_astar_mpd5",
            sha256="3ef7c314b8ca9ea7a303be20dfd4cd9860fc74733b28b0d9a3f8033dacef1436",
            size=None,
            moves="moore",
            description="Neural A*'s encoder trained by vinadv neural-astar train on the five MP families other than "
            "mazes (any map size)",
            metrics=None,
            aliases=("neural_astar_mpd5",),
        ),
    ),
)
TRANSPATH = "vinadv.planners.transpath.planner:load"
TRANSPATH_LICENCE = "MIT, Copyright (c) 2024 AI Research (the TransPath authors, AIRI-Institute/TransPath)"
register(
    "transpath-cf",
    description="TransPath (Kirilenko et al. 2023): A*, octile heuristic divided by a transformer's correction "
    "factors, 64x64 only",
    entry_point=TRANSPATH,
    kwargs={"mode": "cf"},
    default_file="transpath_cf.pt",
    takes_weights=True,
    kind="transpath-cf",
    models=(
        Model(
            name="transpath-cf",
            file="transpath_cf.pt",
            sha256="3300e009d540942930f1465f79e476a0b4642095acfafae4a57017eb9ff8b2f3",
            size=64,
            moves="octile",
            description="TransPath's correction-factor model, converted from the authors' weights/cf.pth",
            licence=TRANSPATH_LICENCE,
            record="transpath_cf.json",
            licence_file="transpath.LICENSE.txt",
        ),
    ),
)
register(
    "transpath-focal",
    description="TransPath (Kirilenko et al. 2023): focal search (f_w 100) on a transformer's focal values, 64x64 only",
    entry_point=TRANSPATH,
    kwargs={"mode": "f"},
    default_file="transpath_focal.pt",
    takes_weights=True,
    kind="transpath-focal",
    models=(
        Model(
            name="transpath-focal",
            file="transpath_focal.pt",
            sha256="d1afeb72367b3b80f76c296cdcab7df8e7eba02ff1c18cb58e2aeeffa457d8c8",
            size=64,
            moves="octile",
            description="TransPath's focal-value model, converted from the authors' weights/focal.pth",
            licence=TRANSPATH_LICENCE,
            record="transpath_focal.json",
            licence_file="transpath.LICENSE.txt",
        ),
    ),
)
