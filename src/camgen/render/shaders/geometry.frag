#version 330 core
uniform uint instance_id;

in float frag_depth_m;

layout(location = 1) out vec4 out_depth_m;
layout(location = 2) out uint out_instance_id;

void main()
{
    out_depth_m = vec4(frag_depth_m, 0.0, 0.0, 1.0);
    out_instance_id = instance_id;
}
