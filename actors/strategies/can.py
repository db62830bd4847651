"""A soda can (66 mm x 122 mm): held around the middle of its body."""
from .base import Approach, Grasp, Strategy

CAN = Strategy(
    category="can",
    approach=Approach(reach=0.27, standoff=0.12),
    grasp=Grasp(height=0.061, pitch=0.0, open_width=0.085, closed_min=0.055, closed_max=0.072,
                lift=0.12),
    description="cylinder held level around the middle of its body (half its height)",
)
