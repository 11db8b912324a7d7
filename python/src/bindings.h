// The parts of the _core module, one per group of core capabilities.
#pragma once

#include <pybind11/pybind11.h>

namespace meshmend::python {

void bindIntersect(
    pybind11::module_& m);              // inspect, intersections, split, self-intersections, files
void bindRepair(pybind11::module_& m);  // holes, trimming, stitching, gap closing
void bindClearance(pybind11::module_& m);  // measuring and enforcing a minimum clearance
void bindPatches(pybind11::module_& m);    // painting, classifying and removing patches

}  // namespace meshmend::python
