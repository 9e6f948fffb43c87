// The transcendentals of op_math.hpp: SLEEF's portable C ("purec") members of the
// deterministic FMA-free family; the VM's vector members are in runtime/eval/vmath.inl.
#include "compiler/ir/op_math.hpp"

#include <sleef.h>

namespace sdfc::om {

float exp_(float a) { return Sleef_cinz_expf1_u10purec(a); }
float log_(float a) { return Sleef_cinz_logf1_u10purec(a); }
float sin_(float a) { return Sleef_cinz_sinf1_u10purec(a); }
float cos_(float a) { return Sleef_cinz_cosf1_u10purec(a); }
float tan_(float a) { return Sleef_cinz_tanf1_u10purec(a); }
float asin_(float a) { return Sleef_cinz_asinf1_u10purec(a); }
float acos_(float a) { return Sleef_cinz_acosf1_u10purec(a); }
float atan_(float a) { return Sleef_cinz_atanf1_u10purec(a); }
float atan2_(float a, float b) { return Sleef_cinz_atan2f1_u10purec(a, b); }
float pow_(float a, float b) { return Sleef_cinz_powf1_u10purec(a, b); }

}  // namespace sdfc::om
