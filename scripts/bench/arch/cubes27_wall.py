# One process: the 27-cube stack of scripts/arch/scenes.py at CELLS^3 cells of 12 tets per cube, STEPS core steps at one thread; timed as a whole process, old build against new, interleaved (bench/logs/arch_s25_wall_old_vs_new.json).
# usage: python3.11 scripts/bench/arch/cubes27_wall.py BUILD/python CELLS STEPS
import sys, os
build, cells, steps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
sys.path[:0] = [build, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "arch")]
from qdem import _core
_core.setThreads(1)
import scenes
w, dt = scenes.cubes27World(cells)
for _ in range(steps):
    w.core.step(dt)
