//! The tape interpreter's text (compiler/glsl/glsl_tape.cpp fills in the @NAME@ lines and
//! words): map() and sdf_material() run their programs from a tape of instructions, one a
//! turn, when the scene is too long for straight-line code. The layout is glsl_tape.hpp's.

// ---- the tape interpreter: the scene's programs as data (layout: sdfc's compiler/glsl/glsl_tape.hpp) ----
@TAPE@
float sdf_reg[@REGS@];

// One cheap instruction at pc, if pc < end and it is one (else `costly` is set and pc stays
// on it, its operands left in op, o, x, y, z, k and kb for sdf_run).
void sdf_step(inout int pc, int end, vec3 p, inout bool costly, inout int op, inout int o, inout float x, inout float y,
              inout float z, inout float k, inout uint kb) {
    if (pc >= end || costly) return;
@DECODE@
    if (@COSTLY@) {
        costly = true;
        return;
    }
    float v = 0.0;
    switch (op) {
@CHEAP_CASES@
        default: break;
    }
    sdf_reg[o] = v;
    ++pc;
}

// Runs instructions [pc, end) at the point p; results stay in sdf_reg. Cheap instructions
// go @UNROLL@ a turn in the inner loop; costly ones (transcendentals, noise, guards) leave it
// for the outer one: CPU drivers run every case of a switch under a lane mask (Mesa
// llvmpipe, SwiftShader), so each case costs every instruction that passes through its
// switch, and llvmpipe ends any shader's loops after 65535 turns in all.
void sdf_run(int pc, int end, vec3 p) {
    int op = 0, o = 0;
    float x = 0.0, y = 0.0, z = 0.0, k = 0.0;
    uint kb = 0u;
    while (pc < end) {
        bool costly = false;
        while (pc < end && !costly) {
@STEPS@
        }
        if (!costly) break;
        float v = 0.0;
        switch (op) {
@COSTLY_CASES@
            default: break;
        }
        sdf_reg[o] = v;
        ++pc;
    }
}
