"""A soda can, 66 mm x 122 mm, red: held level around the middle of its body."""

from categories import Approach, Category, Cylinder, Grasp, Label, register

CATEGORY = register(
    Category(
        name="can",
        shape=Cylinder(radius=0.033, height=0.122),
        mass=0.040,  # empty
        rgba=(0.85, 0.07, 0.07, 1.0),
        grasp=Grasp(height=0.061, open_width=0.085, closed_min=0.055, closed_max=0.072, lift=0.12),
        approach=Approach(reach=0.27, standoff=0.12),
        description="soda can 66 mm x 122 mm, 40 g (empty), red",
        # white lettering over the middle of the body: the can stays mostly red
        label=Label(
            bottom=0.035, top=0.090, rgba=(0.85, 0.07, 0.07, 1.0), print_rgba=(0.95, 0.95, 0.95, 1.0), coverage=0.3
        ),
    )
)
