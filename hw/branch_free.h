// Ring positions and selects in the per-fragment timing recurrences.
// Whether a fragment waits, a cycle is full or a ring wraps follows the
// input; on a trace whose fragments do not arrive in per-object bursts a
// branch there mispredicts often enough to be a large share of the model's
// time, so these are written as masks, which gcc keeps as arithmetic (it
// turns `c ? a : b` back into a branch when it guesses it predictable).
// Measured, not assumed: where the branch predicts (a ring wrapping
// periodically in a run of identical fragments) the branch stays.
#pragma once

namespace rbcd::branch_free {

// The ring position after i in a ring of n.
inline unsigned next(unsigned i, unsigned n) {
    const unsigned j = i + 1;
    return j & (0u - unsigned(j != n));
}

} // namespace rbcd::branch_free
