// ARMSIM_QUICK: an environment switch to try a command quickly, and how the test suite runs the
// README's examples as written (scripts/run_doc_block.py): population-sized loops are capped.
#pragma once

#include <string>

namespace armsim {

/// Subjects a population-sized loop runs under ARMSIM_QUICK=1.
constexpr int kQuickSubjects = 3;

/// Whether ARMSIM_QUICK=1 is set ("0" or unset: no). Throws InputError naming the variable and its value
/// for anything else.
bool isQuickRun();

/// min(value, cap) under ARMSIM_QUICK=1 (writing once per `what` on standard error that it did, so a
/// capped result is never taken for a full one), value otherwise.
int capForQuickRun(int value, int cap, const std::string& what);

}  // namespace armsim
