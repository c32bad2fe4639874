"""Source files of bring-your-own planners (`--planner FILE.py:make`) that the tests write and load."""

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
