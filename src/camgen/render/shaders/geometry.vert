#version 330 core
// camgen: the geometric passes alone (metric depth and instance id), without lighting. It also serves
// pyrender's shadow-map pass, which has no colour attachment, so the outputs are discarded there.
layout(location = 0) in vec3 position;
layout(location = INST_M_LOC) in mat4 inst_m;

uniform mat4 P;
uniform mat4 V;
uniform mat4 M;

out float frag_depth_m;  // distance along the optical axis, interpolated at the pixel centre

void main()
{
    vec4 view_position = V * M * inst_m * vec4(position, 1.0);
    frag_depth_m = -view_position.z;
    gl_Position = P * view_position;
}
