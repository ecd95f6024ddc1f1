// Debug overlay of the SLIM splats: the screen bound of every ball, green where the patch is
// drawn, red where the per-quadric test culls it ([Stoll06] Fig. 3).
flat in int v_culled;
out vec4 out_colour;
void main() { out_colour = v_culled != 0 ? vec4(0.85, 0.15, 0.1, 1.0) : vec4(0.1, 0.6, 0.2, 1.0); }
