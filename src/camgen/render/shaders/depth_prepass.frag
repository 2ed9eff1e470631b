#version 330 core
// camgen: the depth pre-pass of a lit draw (`_PassRenderer.forward`): linear_mesh.vert's positions, no colour
// (the draw masks colour writes); only the depth buffer and the stencil change.
void main()
{
}
