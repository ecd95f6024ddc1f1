// Glyph occluders (glyph_occluder.vert): depth only.
void main() {}
