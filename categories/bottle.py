"""A wine bottle, green: held level low on its body, where it is widest and its weight
sits, so it does not tip in the fingers."""

from categories import Approach, Category, Grasp, Label, Revolution, register

CATEGORY = register(
    Category(
        name="bottle",
        # (top of each section above the base, its radius) [m]: body, shoulder, neck
        shape=Revolution(((0.200, 0.035), (0.230, 0.024), (0.305, 0.0135))),
        # 80 g: an empty PET wine bottle. Much heavier and the extended arm tips the robot
        # onto its nose (its centre of mass is only ~25 mm behind the wheel axle).
        mass=0.08,
        rgba=(0.05, 0.32, 0.12, 1.0),
        grasp=Grasp(height=0.055, open_width=0.085, closed_min=0.060, closed_max=0.078, lift=0.10),
        approach=Approach(reach=0.27, standoff=0.12),
        description="wine-bottle shape: body 70 mm x 200 mm, shoulder, neck 27 mm; 0.305 m, 80 g (empty PET)",
        # a cream paper label around the body: the green shows below it and above it
        label=Label(bottom=0.070, top=0.150),
    )
)
