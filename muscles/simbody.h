// The one header through which armsim includes Simbody.
//
// Debian's Simbody 3.7 was built without NDEBUG, and a Simbody header changes the layout of a class
// when NDEBUG is defined (upstream Simbody issue 701). A translation unit compiled with NDEBUG then
// disagrees with the library and crashes in realizeTopology(). Link the CMake target armsim::simbody,
// which compiles its consumers with -UNDEBUG; this check stops any other build at compile time.
#pragma once

#ifdef NDEBUG
#error "armsim: Simbody must be included with NDEBUG undefined (link armsim::simbody, which adds -UNDEBUG)"
#endif

#include <Simbody.h>
