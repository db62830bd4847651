"""A wine bottle (70 mm body, narrow neck): held low on its body, where it is widest and
its weight sits, so it does not tip in the fingers."""
from .base import Approach, Grasp, Strategy

BOTTLE = Strategy(
    category="bottle",
    approach=Approach(reach=0.27, standoff=0.12),
    grasp=Grasp(height=0.055, pitch=0.0, open_width=0.085, closed_min=0.060, closed_max=0.078,
                lift=0.10),
    description="held level low on the body (55 mm up), below the shoulder",
)
