// SLIM early-depth path (render/passes/slim_pass.h): the depth buffer (what the frame drew before
// SLIM) into the colour target that keeps pass 1's depth, so it holds the depth buffer after
// pass 1 without a copy.
layout(binding = 0) uniform sampler2D u_depth;
layout(location = 0) out float out_pass1_depth;

void main() { out_pass1_depth = texelFetch(u_depth, ivec2(gl_FragCoord.xy), 0).x; }
