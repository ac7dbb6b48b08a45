#!/usr/bin/env python3
"""Every thrust or CUB algorithm of the simulation step is called in the launch layer (sim/src/launch/),
where it is counted (sphxr/sim/launch_counts.h), or in the CPU backend's own code; nowhere else in sim/src.
An algorithm called elsewhere would run uncounted, and cpu-reference would no longer say what CUDA does.

usage: check_launch_layer.py [SIM_SRC]   (default: sim/src beside this script); exit 1 listing the calls.
"""
import pathlib
import re
import sys

ALGORITHMS = (
    "for_each|for_each_n|fill|fill_n|sort|sort_by_key|stable_sort|stable_sort_by_key|gather|gather_if|scatter|"
    "scatter_if|reduce|reduce_by_key|transform|transform_reduce|transform_if|copy|copy_n|copy_if|count|count_if|"
    "exclusive_scan|inclusive_scan|exclusive_scan_by_key|inclusive_scan_by_key|transform_exclusive_scan|"
    "transform_inclusive_scan|sequence|tabulate|unique|unique_copy|remove_if|remove_copy_if|partition|"
    "min_element|max_element|minmax_element|lower_bound|upper_bound|adjacent_difference|uninitialized_fill|"
    "generate|replace|replace_if|all_of|any_of|none_of|equal|inner_product|set_difference|merge"
)
CALL = re.compile(r"\bthrust::(?:[a-z_]+::)*(?:%s)\s*\(|\bcub::Device\w+::\w+\s*\(" % ALGORITHMS)

# Where an algorithm may be called: the launch layer, the CPU backend's own launcher and stages, the
# backends' Traits (their policy and raw reduction, which the launch layer calls).
ALLOWED = ("launch/", "cpu/", "backend_cpu.cpp", "backend_cpu_reference.cpp", "backend_cuda.cu")
# Not through the launch layer yet: the surface (HPMC), whose work counts through the same counter once
# SurfaceImpl takes the backend's DeviceOps (BackendImpl hands it over when SurfaceImpl::UseDevice exists).
NOT_YET = ("surface_impl.h", "surface_stages.h", "solver_surface.cpp")


def main() -> int:
    root = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent / "sim" / "src"
    found = []
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".h", ".cpp", ".cu", ".cuh"):
            continue
        rel = path.relative_to(root).as_posix()
        if rel.startswith(ALLOWED) or rel in ALLOWED or rel in NOT_YET:
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("//", 1)[0]
            if CALL.search(code):
                found.append(f"{rel}:{number}: {line.strip()}")
    if found:
        print("thrust/CUB algorithms called outside the launch layer (sim/src/launch/device.h counts them):")
        print("\n".join(found))
        return 1
    print(f"launch layer: no thrust or CUB algorithm outside sim/src/launch/ and the CPU's own code ({root})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
