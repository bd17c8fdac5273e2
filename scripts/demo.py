#!/usr/bin/env python3
"""demo.sh's program: uav_fault_estimator.chain.demo_run (its docstring says what it does), its
default output folders under the checkout's runs/."""

import sys
from pathlib import Path

from uav_fault_estimator.chain.demo_run import main

if __name__ == "__main__":
    sys.exit(main(Path(__file__).resolve().parent.parent / "runs"))
