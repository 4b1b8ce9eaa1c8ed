// Placeholder until the procedural texture ops land (branch node-tex): every texture op is declined, so a
// program using one is refused by run_program's caller... replaced by the real implementation in the merge.
#include "shader/op_args.h"

namespace ps {

bool run_texture_op(ShaderOp, const OpArgs&, const float*) { return false; }

}  // namespace ps
