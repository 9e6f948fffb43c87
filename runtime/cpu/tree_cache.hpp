// The last tape tree built, kept for the next render that would build the same one: the
// frames of an animation whose distance field stays the same (a turntable, moving lights
// or materials), a scene re-rendered with other settings (`sdfc watch`, the API, `sdfc
// bench`'s repeats). A tree is a function of the distance program (code, output, guards),
// the root box, the time (only when the program reads it), the field's kind and the
// image's sample count (its budgets): the same inputs build the same tree, bit for bit
// (tape_tree.cpp: deterministic for any thread count), so a reused tree changes no pixel.
// One tree at a time, shared read-only by the renders using it (never changed after it
// is built); a render with other inputs replaces it.
#pragma once
#include <cstddef>
#include <memory>

#include <glm/glm.hpp>

#include "compiler/bytecode/program.hpp"
#include "runtime/cpu/tape_tree.hpp"

namespace sdfc::cpu {

// build_tree's inputs besides the program.
struct TreeInputs {
    glm::vec3 lo{0}, hi{0};
    float time = 0.0f;
    bool lipschitz = true;
    size_t samples = 0;
    bool thin_layer = false;
};

// The tree for `p` and `in`: the kept one when it was built from the same inputs (then
// *reused is set), else a new one from build_tree (call inside the render's task arena),
// kept in its place when `keep`. Thread-safe; builds run outside the lock.
std::shared_ptr<const TapeTree> shared_tree(const Program& p, const TreeInputs& in, bool keep, bool* reused = nullptr);

// Drops the kept tree (its memory goes when the last render using it ends).
void forget_tree();

}  // namespace sdfc::cpu
