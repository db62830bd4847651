"""Small helpers that more than one of the plain libraries needs, kept here once because
those libraries may not import each other (docs/architecture.md, "The layers"): ``sim``
and ``planning`` both drive pybullet, ``sim`` and ``navstack`` both read map images.

    quiet_pybullet  pybullet imported without its build banner
    pgm             PGM images (P5 and P2, 8 or 16 bit) as arrays of lightness

It imports none of the repository's packages.
"""
