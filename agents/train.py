"""Thin script: ``python agents/train.py --algo ppo --env vfgym/VFTune-v0`` = ``vfgym train``."""

import sys

from vfgym.cli import main

if __name__ == "__main__":
    sys.exit(main(["train", *sys.argv[1:]]))
