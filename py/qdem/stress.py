"""Stress measures shared by output, plots and the Piece handle."""
import numpy as np


def vonMises(s):
    """Von Mises stress of Cauchy stresses given as rows (xx, yy, zz, yz, xz, xy)."""
    s = np.asarray(s)
    return np.sqrt(0.5 * ((s[:, 0] - s[:, 1])**2 + (s[:, 1] - s[:, 2])**2 + (s[:, 2] - s[:, 0])**2)
                   + 3.0 * (s[:, 3]**2 + s[:, 4]**2 + s[:, 5]**2))
