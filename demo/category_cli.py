"""`actorbt category ...`: the object categories against this robot (a plugin named in
actorbt.yaml).

    actorbt category list
    actorbt category check FILE.py [FILE.py ...]

``check`` loads each category file as ``imports`` would and says whether it can work on
this robot: every grasp within the arm's reach, the stall window around the object
(categories/check.py, actors/category_check.py); what was derived; and, when it cannot,
what to change.
"""

from __future__ import annotations

import argparse
import math
import sys


def register(sub, common) -> None:
    p = sub.add_parser(
        "category",
        help="object categories: list them, check a category file",
        description="The object categories the robot knows (can, bottle, carton and "
        "the ones actorbt.yaml imports), and a check of a category file "
        "against the robot: reach, stall window, opening.",
    )
    catsub = p.add_subparsers(dest="category_command", metavar="CATEGORY_COMMAND")
    catsub.required = True
    ls = catsub.add_parser(
        "list",
        help="the registered categories, one line each",
        description="The categories registered now: the built-ins and the ones "
        "actorbt.yaml's imports add, with their descriptions.",
    )
    ls.set_defaults(func=cmd_list)
    c = catsub.add_parser(
        "check",
        help="check category files against the robot (exit 1 when one cannot work)",
        description="Load each category file and check every grasp it declares against the arm's "
        "kinematics and the gripper: upright at approach.reach (the grasp, the test "
        "lift, the lift), lying from above, and the stall window around the width "
        "the fingers close on. Prints the grasps, or what to change.",
    )
    c.add_argument("files", nargs="+", metavar="FILE.py", help="Category files (as actorbt.yaml's imports names them).")
    c.set_defaults(func=cmd_check)


def _declared(file: str) -> list:
    """The categories a category file's module holds (it was imported before)."""
    from bt_engine.modules import import_file, is_file_reference
    from categories import Category

    if not is_file_reference(file):
        return []
    module = import_file(file)
    return [v for v in vars(module).values() if isinstance(v, Category)]


def cmd_list(args: argparse.Namespace, app) -> int:
    import categories

    for cat in categories.all_categories():
        print(f"{cat.name:<12} {cat.description}")
    return 0


def cmd_check(args: argparse.Namespace, app) -> int:
    import categories
    from categories.check import plan_text

    from actors.category_check import problems_of

    failed = 0
    for file in args.files:
        try:
            loaded = categories.load(file)
        except categories.CategoryError as e:
            print(f"error: {e}", file=sys.stderr)
            failed += 1
            continue
        if not loaded:  # imported already (actorbt.yaml's imports): what it declares
            loaded = _declared(file)
        if not loaded:
            print(
                f"error: {file}: registers no category (expected CATEGORY = register(Category(...)))", file=sys.stderr
            )
            failed += 1
            continue
        for cat in loaded:
            problems = problems_of(cat)
            if problems:
                where = categories.declared_at(cat.name) or file
                print(
                    f"error: {where}: category {cat.name!r} cannot work on this robot: {'; '.join(problems)}",
                    file=sys.stderr,
                )
                failed += 1
                continue
            s = cat.strategy
            print(f"{file}: category {cat.name!r} can work on this robot")
            print(f"  upright: {plan_text(s.upright)}, lift {cat.grasp.lift:.3f} m")
            for plan in s.lying:
                print(f"  lying:   {plan_text(plan)}")
            if not s.lying:
                print("  lying:   no grasp (its body does not fit the open hand from above)")
            print(
                f"  the fingers close on {cat.held_width() * 1000:.0f} mm at grasp.height "
                f"{cat.grasp.height:.3f} m; sides: "
                f"{'any' if not s.sides else ', '.join(f'{math.degrees(h):.0f} deg' for h in s.sides)}"
            )
    return 1 if failed else 0
