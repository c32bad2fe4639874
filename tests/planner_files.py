"""Source files of bring-your-own planners (`--planner FILE.py:make`) that the tests write and load, and a small
GPPN's weights file (`write_gppn`)."""

import torch

from vinadv.planners.gppn import GPPN, GPPNConfig, save_gppn

#: a planner without parameters or buffers: no weights, so no weights checksum
NO_PARAMETERS = """
import torch


class Straight(torch.nn.Module):
    def forward(self, obstacles, goals):
        return torch.zeros(obstacles.shape[0], 8, obstacles.shape[1], obstacles.shape[2])


def make(size):
    return Straight()
"""


#: a planner whose forward ends the process (`sys.exit(0)`): vinadv must not exit 0 with it
EXITING = """
import sys

import torch


class Exiting(torch.nn.Module):
    def forward(self, obstacles, goals):
        sys.exit(0)


def make(size):
    return Exiting()
"""


def write_gppn(path, size: int, seed: int = 3) -> str:
    """Write a small untrained GPPN's weights (k 6, l_h 5, f 3; recorded as made for `size`) to `path`; its path."""
    torch.manual_seed(seed)
    save_gppn(GPPN(GPPNConfig(k=6, l_h=5, f=3)), path, {"size": size})
    return str(path)
