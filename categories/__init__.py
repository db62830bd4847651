"""Object categories: one file per kind of object (its simulated body, its look for
perception, its approach and grasp). ``can``, ``bottle`` and ``carton`` are built in;
``load("path/juice.py")`` or the ``imports`` line of actorbt.yaml adds more.
See docs/categories.md for a worked example.

This package is a plain library: the simulator and the robot's actors both read it.
"""

from __future__ import annotations

from .category import Category
from .registry import (
    BUILT_IN,
    CategoryError,
    UnknownCategoryError,
    all_categories,
    declared_at,
    get,
    load,
    names,
    register,
    unregister,
)
from .shapes import Box, Cylinder, Label, Revolution, Shape
from .strategy import Approach, Grasp, GraspPlan, Strategy, TopGrasp

for _module in BUILT_IN:
    load(_module)

__all__ = [
    "Approach",
    "BUILT_IN",
    "Box",
    "Category",
    "CategoryError",
    "Cylinder",
    "Grasp",
    "GraspPlan",
    "Label",
    "Revolution",
    "Shape",
    "Strategy",
    "TopGrasp",
    "UnknownCategoryError",
    "all_categories",
    "declared_at",
    "get",
    "load",
    "names",
    "register",
    "unregister",
]
