//! The html page's entry point (compiler/glsl/glsl.cpp appends it to the page's shader): the
//! passes page.js draws. Progressive: a quick low-resolution picture of one sample first, then
//! each sample of the full picture in bands, summed in a float texture, shown after each band.

uniform int uPass;         // 0: every sample, display-ready; 1: sample uSample; 2: show the sum
uniform int uSample;       // pass 1: which of SDF_SAMPLES
uniform sampler2D uSum;    // pass 2: the samples' weighted radiance summed (alpha: their weight)
uniform sampler2D uQuick;  // pass 2: the quick picture, where the sum has nothing yet

void main() {
    if (uPass == 2) {
        vec4 a = texelFetch(uSum, ivec2(gl_FragCoord.xy), 0);
        if (!(a.a > 0.0)) a = texture(uQuick, gl_FragCoord.xy / iResolution.xy);
        sdf_frag_color = a.a > 0.0 ? sdf_display(a.rgb / a.a) : vec4(0.07, 0.07, 0.07, 1.0);
    } else if (uPass == 1) {
        sdf_frag_color = vec4(sdf_sample_radiance(gl_FragCoord.xy, iResolution.xy, iTime, uOrbit, uPan, uSample), SDF_SAMPLE_WEIGHT);
    } else {
        sdf_frag_color = sdf_render(gl_FragCoord.xy, iResolution.xy, iTime, uOrbit, uPan);
    }
}
