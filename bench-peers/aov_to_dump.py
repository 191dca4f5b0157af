#!/usr/bin/env python3
"""Convert bareray's `render --aov depth,id` EXR (channels Z and id) into a BRDUMP1 file for compare_dump.py.

usage: aov_to_dump.py OUT.aov.exr DUMP.bin      (needs the `OpenEXR` and `numpy` Python packages)
"""
import sys

import numpy as np
import OpenEXR

from compare_dump import write_dump

ch = OpenEXR.File(sys.argv[1]).channels()
t = np.asarray(ch["Z"].pixels, dtype=np.float32)
ids = np.asarray(ch["id"].pixels)
# The id channel is f32 (exact below 2^24 primitives, −1 on a miss) or u32 (0xFFFFFFFF on a miss).
ids = ids.astype(np.int64)
ids[ids == 0xFFFFFFFF] = -1
write_dump(sys.argv[2], t, ids.astype(np.int32))
