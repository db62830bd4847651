"""A juice carton, 70 x 45 x 120 mm, yellow: held level across its narrow side.

Written as a user would write a new category (docs/categories.md): a shape, a mass, a
colour, and how to hold it.
"""

from categories import Approach, Box, Category, Grasp, register

CATEGORY = register(
    Category(
        name="carton",
        shape=Box(x=0.070, y=0.045, z=0.120),
        mass=0.060,
        rgba=(0.95, 0.75, 0.08, 1.0),
        # across the 45 mm side, halfway up; stalled fingers at 35..55 mm mean it is held
        grasp=Grasp(height=0.060, open_width=0.085, closed_min=0.035, closed_max=0.058, lift=0.12),
        approach=Approach(reach=0.27, standoff=0.12),
        description="juice carton 70 x 45 x 120 mm, 60 g, yellow",
    )
)
