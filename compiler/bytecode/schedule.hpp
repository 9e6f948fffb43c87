// The order codegen emits a program's instructions in. Without guarded regions it is node
// order (the IR numbers nodes as they are made, so operands come first). With them
// (compiler/ir/ir.hpp GuardRegion), each region's instructions are one block after its
// guard, nested as the regions nest, so that an evaluator can jump over the block.
//
// A node belongs to the innermost region that holds every use of it (a guard's use of its
// threshold and point counts in the region around the guard); a region's roots belong to it.
// A region is kept only if its roots are used in the region around it and nowhere else, so
// a skipped block leaves nothing stale that runs: the root gets +inf from its guard, the
// other roots (material channels) are read only by the union's choice, which never picks
// them then. Where the graph breaks that (a subexpression shared across regions), the
// result is node order without guards.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "compiler/ir/ir.hpp"

namespace sdfc {

struct ScheduleStep {
    enum Kind : uint8_t { Node, Guard, End } kind;
    uint32_t id;  // Node: the node; Guard: the region (Graph::guards) whose guard and block start; End: whose block ends
};

// `emit[i]`: node i becomes an instruction; `args[i]`: its operands after instruction
// selection (kNoNode for none). Constants are loaded where they are used, so they are not
// scheduled. `regions`: the graph's regions to try (their roots are emitted). Returns the
// steps in order, or an empty list for node order without guards.
std::vector<ScheduleStep> schedule_guarded(const Graph& g, const std::vector<uint8_t>& emit,
                                           const std::vector<std::array<NodeId, 3>>& args, const std::vector<NodeId>& roots,
                                           const std::vector<int32_t>& regions);

}  // namespace sdfc
