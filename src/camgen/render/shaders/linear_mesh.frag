#version 330 core
#extension GL_ARB_texture_gather : require
// camgen: pyrender 0.1.45's mesh.frag (MIT licence, (c) Matthew Matl) changed to write linear,
// unclamped radiance (no gamma, no clamp), metric depth and the instance id into three render targets,
// to add the emissive factor once (pyrender multiplies it by itself), to filter shadow maps with 3 x 3
// bilinear taps (16 comparisons, texture2DShadowPCF) instead of pyrender's 36, which doubled the cost of a
// frame on llvmpipe, under depth biases set in metres for each kind of map (shadow_calc_ortho, shadow_calc_spot),
// and to make the diffuse term Lambertian (rho/pi; pyrender scales it by 0.96 (1 - F)) with no light
// leaking onto faces turned away (pyrender floors n.l at 0.001).
///////////////////////////////////////////////////////////////////////////////
// Structs
///////////////////////////////////////////////////////////////////////////////

struct SpotLight {
    vec3 color;
    float intensity;
    float range;
    vec3 position;
    vec3 direction;
    float light_angle_scale;
    float light_angle_offset;

    #ifdef SPOT_LIGHT_SHADOWS
    sampler2D shadow_map;
    mat4 light_matrix;
    #endif
};

// camgen: a sun's shadow maps after its first, each coarser than the one before (cascades split along the
// view's depth: camgen.render.renderer.sun_cascade_matrices, whose SUN_CASCADES is one more than this).
const int SUN_EXTRA_CASCADES = 2;

struct DirectionalLight {
    vec3 color;
    float intensity;
    vec3 direction;

    #ifdef DIRECTIONAL_LIGHT_SHADOWS
    mat4 light_matrix;
    // camgen: every cascade's map, one layer each, finest first (pyrender's own shadow_map is not read):
    // one sampler whose layer a pixel chooses, where a map per cascade behind branches cost llvmpipe a
    // filtered lookup in each (camgen.render.renderer._PassRenderer._sun_cascade_array).
    sampler2DArray shadow_maps;
    mat4 cascade_matrices[SUN_EXTRA_CASCADES];
    // camgen: each cascade's (finest first) depth scale (the length of the first three entries of row 2 of
    // its P·V) and texel in metres (the coarser of its two axes'), for shadow_calc_ortho's bias, worked out
    // once per draw (`_PassRenderer._bind_lighting`, `sun_cascade_scales`) instead of at every pixel.
    vec2 cascade_scales[SUN_EXTRA_CASCADES + 1];
    #endif
};

struct PointLight {
    vec3 color;
    float intensity;
    float range;
    vec3 position;

    #ifdef POINT_LIGHT_SHADOWS
    samplerCube shadow_map;
    #endif
};

struct Material {
    vec3 emissive_factor;

#ifdef USE_METALLIC_MATERIAL
    vec4 base_color_factor;
    float metallic_factor;
    float roughness_factor;
#endif

#ifdef USE_GLOSSY_MATERIAL
    vec4 diffuse_factor;
    vec3 specular_factor;
    float glossiness_factor;
#endif

#ifdef HAS_NORMAL_TEX
    sampler2D normal_texture;
#endif
#ifdef HAS_OCCLUSION_TEX
    sampler2D occlusion_texture;
#endif
#ifdef HAS_EMISSIVE_TEX
    sampler2D emissive_texture;
#endif
#ifdef HAS_BASE_COLOR_TEX
    sampler2D base_color_texture;
#endif
#ifdef HAS_METALLIC_ROUGHNESS_TEX
    sampler2D metallic_roughness_texture;
#endif
#ifdef HAS_DIFFUSE_TEX
    sampler2D diffuse_texture;
#endif
#ifdef HAS_SPECULAR_GLOSSINESS_TEX
    sampler2D specular_glossiness;
#endif
};

struct PBRInfo {
    float nl;
    float nv;
    float nh;
    float lh;
    float vh;
    float roughness;
    float metallic;
    vec3 f0;
    vec3 c_diff;
};

///////////////////////////////////////////////////////////////////////////////
// Uniforms
///////////////////////////////////////////////////////////////////////////////
uniform Material material;
uniform PointLight point_lights[MAX_POINT_LIGHTS];
uniform int n_point_lights;
uniform DirectionalLight directional_lights[MAX_DIRECTIONAL_LIGHTS];
uniform int n_directional_lights;
uniform SpotLight spot_lights[MAX_SPOT_LIGHTS];
uniform int n_spot_lights;
// camgen: a spot light's tabulated intensity (an IES file, camgen.world.ies). Row k > 0: the light's
// I(gamma, C) / I_max is band k - 1 of spot_profile (C every 5 deg across, gamma every 1 deg up each
// band of 181 texels), looked up in its axes (rows: the C = 0 direction, C = 90, the gamma = 0 axis);
// 0: the glTF cone of light_angle_scale and light_angle_offset.
uniform int spot_profile_row[MAX_SPOT_LIGHTS];
uniform mat3 spot_profile_axes[MAX_SPOT_LIGHTS];
uniform sampler2D spot_profile;
uniform vec3 cam_pos;
// camgen: added to every material texture's level of detail. A sub-frame drawn at 1x that stands for s x s
// samples of a pixel (motion blur's jittered draws) takes -log2(s), the level an s x supersampled draw
// picks; without it its textures came out a mip level blurrier than the same frame without motion blur.
uniform float texture_lod_bias;
// camgen: glass (a blended material) is drawn by a program of its own, with the define of the see-through
// path: the base colour's alpha is the opacity 1 - T at normal incidence (T the pane's visible transmittance,
// camgen.vehicles.cabin); see the end of main. A clear-coated material (camgen.render.scene_graph.
// ClearcoatMaterial: a car's paint) too, with the define of clearcoat_ambient's path. Defines of the
// material's program (`_LinearProgramCache.material_kind`; pyrender replaces a define's name wherever it
// appears, so they are named only where tested), not uniforms: llvmpipe ran both sides of a branch on a
// uniform, and the two paths' sky lookups cost every surface that has neither 26 % of a sunlit draw of
// the parking lot.
uniform vec3 ambient_light;
// camgen: the sky's radiance over the upper hemisphere (camgen.render.renderer.SkyMap: a CIE sky, azimuth
// across, elevation 0 to 90 deg up), which smooth coats and glass mirror; sky_map_used 0: a uniform sky
// of radiance ambient_light.
uniform sampler2D sky_map;
uniform int sky_map_used;
uniform uint instance_id;

#ifdef USE_IBL
uniform samplerCube diffuse_env;
uniform samplerCube specular_env;
#endif

///////////////////////////////////////////////////////////////////////////////
// Inputs
///////////////////////////////////////////////////////////////////////////////

in vec3 frag_position;
in float frag_depth_m;
#ifdef NORMAL_LOC
in vec3 frag_normal;
#endif
#ifdef HAS_NORMAL_TEX
#ifdef TANGENT_LOC
#ifdef NORMAL_LOC
in mat3 tbn;
#endif
#endif
#endif
#ifdef TEXCOORD_0_LOC
in vec2 uv_0;
#endif
#ifdef TEXCOORD_1_LOC
in vec2 uv_1;
#endif
#ifdef COLOR_0_LOC
in vec4 color_multiplier;
#endif

///////////////////////////////////////////////////////////////////////////////
// OUTPUTS
///////////////////////////////////////////////////////////////////////////////

layout(location = 0) out vec4 out_radiance;
layout(location = 1) out vec4 out_depth_m;
layout(location = 2) out uint out_instance_id;

///////////////////////////////////////////////////////////////////////////////
// Constants
///////////////////////////////////////////////////////////////////////////////
const float PI = 3.141592653589793;
const float min_roughness = 0.04;

///////////////////////////////////////////////////////////////////////////////
// Utility Functions
///////////////////////////////////////////////////////////////////////////////
vec4 srgb_to_linear(vec4 srgb)
{
#ifndef SRGB_CORRECTED
    // Fast Approximation
    //vec3 linOut = pow(srgbIn.xyz,vec3(2.2));
    //
    vec3 b_less = step(vec3(0.04045),srgb.xyz);
    vec3 lin_out = mix( srgb.xyz/vec3(12.92), pow((srgb.xyz+vec3(0.055))/vec3(1.055),vec3(2.4)), b_less );
    return vec4(lin_out, srgb.w);
#else
    return srgb;
#endif
}

// Normal computation
vec3 get_normal()
{
#ifdef HAS_NORMAL_TEX

#ifndef HAS_TANGENTS
    vec3 pos_dx = dFdx(frag_position);
    vec3 pos_dy = dFdy(frag_position);
    vec3 tex_dx = dFdx(vec3(uv_0, 0.0));
    vec3 tex_dy = dFdy(vec3(uv_0, 0.0));
    vec3 t = (tex_dy.t * pos_dx - tex_dx.t * pos_dy) / (tex_dx.s * tex_dy.t - tex_dy.s * tex_dx.t);

#ifdef NORMAL_LOC
    vec3 ng = normalize(frag_normal);
#else
    vec3 = cross(pos_dx, pos_dy);
#endif

    t = normalize(t - ng * dot(ng, t));
    vec3 b = normalize(cross(ng, t));
    mat3 tbn_n = mat3(t, b, ng);

#else

    mat3 tbn_n = tbn;

#endif

    vec3 n = texture(material.normal_texture, uv_0, texture_lod_bias).rgb;
    n = normalize(tbn_n * ((2.0 * n - 1.0) * vec3(1.0, 1.0, 1.0)));
    return n; // TODO NORMAL MAPPING

#else

#ifdef NORMAL_LOC
    return frag_normal;
#else
    return normalize(cam_pos - frag_position);
#endif

#endif
}

// Fresnel
vec3 specular_reflection(PBRInfo info)
{
     vec3 res = info.f0 + (1.0 - info.f0) * pow(clamp(1.0 - info.vh, 0.0, 1.0), 5.0);
     return res;
}

// Smith
float geometric_occlusion(PBRInfo info)
{
    float r = info.roughness + 1.0;
    float k = r * r  / 8.0;
    float g1 = info.nv / (info.nv * (1.0 - k) + k);
    float g2 = info.nl / (info.nl * (1.0 - k) + k);
    //float k = info.roughness * sqrt(2.0 / PI);
    //float g1 = info.lh / (info.lh * (1.0 - k) + k);
    //float g2 = info.nh / (info.nh * (1.0 - k) + k);
    return g1 * g2;
}

float microfacet_distribution(PBRInfo info)
{
    float a = info.roughness * info.roughness;
    float a2 = a * a;
    float nh2 = info.nh * info.nh;

    float denom = (nh2 * (a2 - 1.0) + 1.0);
    return a2 / (PI * denom * denom);
}

vec3 compute_brdf(vec3 n, vec3 v, vec3 l,
                  float roughness, float metalness,
                  vec3 f0, vec3 c_diff, vec3 albedo,
                  vec3 radiance)
{
        vec3 h = normalize(l+v);
        float nl = clamp(dot(n, l), 0.0, 1.0);
        float nv = clamp(abs(dot(n, v)), 0.001, 1.0);
        float nh = clamp(dot(n, h), 0.0, 1.0);
        float lh = clamp(dot(l, h), 0.0, 1.0);
        float vh = clamp(dot(v, h), 0.0, 1.0);

        PBRInfo info = PBRInfo(nl, nv, nh, lh, vh, roughness, metalness, f0, c_diff);

        // Compute PBR terms
        vec3 F = specular_reflection(info);
        float G = geometric_occlusion(info);
        float D = microfacet_distribution(info);

        // Compute BRDF
        vec3 diffuse_contrib = c_diff / PI;  // Lambertian: L = rho E cos(theta) / pi
        vec3 spec_contrib = F * G * D / (4.0 * nl * nv + 0.001);

        vec3 color = nl * radiance * (diffuse_contrib + spec_contrib);
        return color;
}

// camgen: percentage-closer filtering (Reeves, Salesin and Cook 1987, "Rendering antialiased shadows with
// depth maps"), the mean of 3 x 3 bilinear lookups one texel apart: a kernel four texels wide whose weights
// fall off smoothly, so a shadow's edge is a soft ramp instead of following the map's texel staircase (the
// sun's map spreads 2048 texels over a whole site: 3-4 cm each, a jagged outline around every pedestrian's
// shadow). The nine lookups touch a 4 x 4 block of texels with separable weights (1 - f, 1, 1, f) / 3 per
// axis: sixteen comparisons instead of thirty-six, the same result. The sixteen depths are fetched by four
// gathers (textureGather: the 2 x 2 texels a bilinear lookup at a texel corner reads, raw), not sixteen
// lookups: the same depths and comparisons in a third of the fetches (on llvmpipe the sixteen lookups
// were 40 % of a sunlit 1080p draw). A map's size is a power of two, so a corner's coordinate is exact.
vec4 shadowed_2x2(sampler2D depths, vec2 corner_uv, float compare) {
    // 1 where the point lies behind the map's depth, in gather order: (i0, j1), (i1, j1), (i1, j0), (i0, j0)
    return vec4(greaterThan(vec4(compare), textureGather(depths, corner_uv)));
}

vec4 shadowed_2x2_layer(sampler2DArray depths, float layer, vec2 corner_uv, float compare) {
    return vec4(greaterThan(vec4(compare), textureGather(depths, vec3(corner_uv, layer))));
}

// texture2DShadowPCF on one layer of an array of maps (a sun's cascades): the same texels and sums.
float texture2DArrayShadowPCF(sampler2DArray depths, float layer, vec2 size, vec2 uv, float compare) {
    vec2 texel = vec2(1.0) / size;
    vec2 st = uv * size - 0.5;
    vec2 f = fract(st);
    vec2 corner = floor(st) * texel;
    vec4 low_left = shadowed_2x2_layer(depths, layer, corner, compare);
    vec4 low_right = shadowed_2x2_layer(depths, layer, corner + vec2(2.0, 0.0) * texel, compare);
    vec4 high_left = shadowed_2x2_layer(depths, layer, corner + vec2(0.0, 2.0) * texel, compare);
    vec4 high_right = shadowed_2x2_layer(depths, layer, corner + vec2(2.0, 2.0) * texel, compare);
    vec4 wx = vec4(1.0 - f.x, 1.0, 1.0, f.x);
    vec4 wy = vec4(1.0 - f.y, 1.0, 1.0, f.y);
    float sum = 0.0;
    sum += wy[0] * dot(wx, vec4(low_left.w, low_left.z, low_right.w, low_right.z));
    sum += wy[1] * dot(wx, vec4(low_left.x, low_left.y, low_right.x, low_right.y));
    sum += wy[2] * dot(wx, vec4(high_left.w, high_left.z, high_right.w, high_right.z));
    sum += wy[3] * dot(wx, vec4(high_left.x, high_left.y, high_right.x, high_right.y));
    return sum / 9.0;
}

float texture2DShadowPCF(sampler2D depths, vec2 size, vec2 uv, float compare) {
    vec2 texel = vec2(1.0) / size;
    vec2 st = uv * size - 0.5;
    vec2 f = fract(st);
    vec2 corner = floor(st) * texel;  // between the texels at offsets -1 and 0 on each axis
    vec4 low_left = shadowed_2x2(depths, corner, compare);  // columns -1, 0; rows -1, 0
    vec4 low_right = shadowed_2x2(depths, corner + vec2(2.0, 0.0) * texel, compare);  // columns 1, 2
    vec4 high_left = shadowed_2x2(depths, corner + vec2(0.0, 2.0) * texel, compare);  // rows 1, 2
    vec4 high_right = shadowed_2x2(depths, corner + vec2(2.0, 2.0) * texel, compare);
    vec4 wx = vec4(1.0 - f.x, 1.0, 1.0, f.x);
    vec4 wy = vec4(1.0 - f.y, 1.0, 1.0, f.y);
    float sum = 0.0;
    sum += wy[0] * dot(wx, vec4(low_left.w, low_left.z, low_right.w, low_right.z));  // row -1
    sum += wy[1] * dot(wx, vec4(low_left.x, low_left.y, low_right.x, low_right.y));  // row 0
    sum += wy[2] * dot(wx, vec4(high_left.w, high_left.z, high_right.w, high_right.z));  // row 1
    sum += wy[3] * dot(wx, vec4(high_left.x, high_left.y, high_right.x, high_right.y));  // row 2
    return sum / 9.0;
}

// camgen: a spot light's shadow map is perspective (pyrender's camera at the lamp: a field of view of twice
// the cone plus 11.25 deg, 2048 texels across), filtered like the sun's (texture2DShadowPCF). Its depth bias is
// the receiver plane's own climb over the kernel's reach (slope-scaled bias, as in Dou et al. 2014, "Adaptive
// depth bias for shadow maps", JCGT 3(4), written out for a perspective map): in the light's view frame a plane
// with unit normal n (towards the lamp), met at distance r along the ray of a point at axial depth D, has an
// axial depth whose reciprocal is linear across the map, and between the lookup and a texel (dx, dy) texels
// away it comes nearer by at most D^2 / (r n.l) * (2 / size) * tan(fov / 2) * |n_x dx + n_y dy| (n_x, n_y its
// components across the map's axes). The kernel's 4 x 4 texels lie within 2 texels of the lookup on each
// axis, so the bias is that with |dx| = |dy| = 2 (exact for a plane, zero for a plane square to the axis: the
// ground under a lamp that points straight down), plus 5 mm for meshes that are not one plane and for the
// depth buffer's precision (24 bits or a float over a near plane at 1 % of the scene's diagonal: under 0.1 mm
// where lamps light). n.l is floored at 0.1 as the sun's is (a face nearly edge-on to the lamp spans few texels
// over a deep range and gets under a tenth of its light). The normal is the face's (the depth map holds the
// faces, not the interpolated normals), from screen-space derivatives taken in main (uniform control flow).
// The bias is applied exactly, in metres, by moving the point that far nearer along its own ray from the lamp:
// the same texel, and the depth the map would store there (its depth is not linear in distance). pyrender's
// bias, 0.001 (1 - n.l) of the window depth over w (at most 6 mm 8 m from the night street's lamps), does not
// grow with the slope: with it even pyrender's one lookup left the hedge's and the houses' street faces,
// nearly along the lamps' axes, in their own shadow.
const float SPOT_SHADOW_MIN_COS = 0.1;
const float SPOT_SHADOW_BIAS_M = 0.005;

float shadow_calc_spot(mat4 light_matrix, sampler2D shadow_map, vec3 light_position, vec3 face_normal)
{
    vec4 proj_coords = light_matrix * vec4(frag_position, 1.0);
    // A point at or behind the spot light's plane (w <= 0) is outside its frustum and unlit by it; dividing
    // by w there made inf, and 0 * inf a NaN in the pixel (a wall above a street lamp).
    if (proj_coords.w <= 1e-6) {
        return 0.0;
    }
    float depth_m = proj_coords.w;  // the point's depth along the lamp's axis (w = -z of the light's view)
    vec3 to_light = light_position - frag_position;
    float distance_m = length(to_light);
    vec3 normal = dot(face_normal, to_light) < 0.0 ? -face_normal : face_normal;
    float nl = max(dot(normal, to_light) / distance_m, SPOT_SHADOW_MIN_COS);
    vec2 size = vec2(textureSize(shadow_map, 0));
    // The rows of light_matrix = P V: P's first two are the map's axes over tan(fov / 2).
    vec3 row_x = vec3(light_matrix[0][0], light_matrix[1][0], light_matrix[2][0]);
    vec3 row_y = vec3(light_matrix[0][1], light_matrix[1][1], light_matrix[2][1]);
    float climb_m = 4.0 * depth_m * depth_m / (distance_m * nl)
        * (abs(dot(normal, row_x)) / (size.x * dot(row_x, row_x)) + abs(dot(normal, row_y)) / (size.y * dot(row_y, row_y)));
    float bias_m = min(SPOT_SHADOW_BIAS_M + climb_m, 0.5 * depth_m);
    vec4 biased = light_matrix * vec4(frag_position + to_light * (bias_m / depth_m), 1.0);
    vec3 light_coords = proj_coords.xyz / proj_coords.w * 0.5 + 0.5;
    float compare = biased.z / biased.w * 0.5 + 0.5;
    float shadow = texture2DShadowPCF(shadow_map, size, light_coords.xy, compare);
    if (light_coords.z > 1.0) {
        shadow = 0.0;
    }
    return shadow;
}

// camgen: a sun's shadow map is orthographic (camgen.render.renderer.directional_shadow_matrices), so
// its bias is set in metres: 5 mm plus four texels of the surface's depth slope, converted to depth
// units through the map's own scale (rows of light_matrix = P·V, V a rotation). The PCF kernel
// (texture2DShadowPCF) compares texels up to 2 texels from the lookup along each map axis, 2√2 along a
// diagonal, and a lit surface must not shadow itself there (with 1.5 texels a flat sunlit ground under a
// high sun showed stripes down to 0.85 of its light; with 3, the far cascade of a 400 m ground 72 m away
// one row of dots at 0.998: the rasterised depth of a plane clipped far outside the map slopes a little
// off). The texel is the coarser of the map's two axes'. pyrender's bias, 0.001 (1 − n·l) of the
// map's depth range, grew with the scene: tens of centimetres of detached shadow on a large site.
float shadow_calc_ortho(vec3 ndc, sampler2DArray shadow_maps, float layer, vec2 scales, float nl)
{
    vec3 light_coords = ndc * 0.5 + 0.5;
    vec2 size = vec2(textureSize(shadow_maps, 0).xy);
    float tan_incidence = sqrt(max(1.0 - nl * nl, 0.0)) / max(nl, 0.1);
    float bias_m = 0.005 + 4.0 * scales.y * tan_incidence;
    float compare = light_coords.z - bias_m * 0.5 * scales.x;
    float shadow = texture2DArrayShadowPCF(shadow_maps, layer, size, light_coords.xy, compare);
    if (light_coords.z > 1.0) {
        shadow = 0.0;
    }
    return shadow;
}

// camgen: whether a sun's (orthographic) map holds a point of map coordinates `ndc` with the filter's reach
// (texture2DShadowPCF reaches 2 texels from the lookup; 3 kept): the shader takes the finest cascade that does.
bool in_sun_cascade(vec2 ndc, sampler2DArray shadow_maps)
{
    float margin = 2.0 * 3.0 / float(textureSize(shadow_maps, 0).x);
    return all(lessThan(abs(ndc), vec2(1.0 - margin)));
}

// camgen: the ambient light of a clear-coated material (a car's paint). The coat is a smooth dielectric of
// refractive index 1.5 over the base: Schlick's Fresnel reflectance F = F0 + (1 - F0)(1 - n.v)^5, F0 = 0.04
// (glTF KHR_materials_clearcoat), mirrors the environment along the reflected ray, and the base's diffuse
// ambient term keeps the share (1 - F) (the light the coat lets in and out; the layering of Filament's clear
// coat model, Guy & Agopian, "Physically Based Rendering in Filament", 2018, section 4.9). The environment
// is the sky above the horizon, its radiance along the reflected ray (sky_along: the scene's CIE sky, brighter
// towards the horizon and the sun, bluer away from it; a uniform sky's radiance ambient_light, a uniform sky of
// illuminance E having radiance E / pi, camgen.render.scene_graph), and below it the ground, a Lambertian surface of albedo
// CLEARCOAT_GROUND_ALBEDO lit by that sky and the suns, blended over the reflected ray's elevation as the
// glass's reflection is (sky_share: fully sky from 11.5 deg up, ground from 11.5 deg down: buildings and
// trees break the horizon). At normal incidence the coat adds 4 % of the sky; at grazing views (a roof or
// bonnet seen from a distant camera, a car's flanks towards the horizon) it mirrors most of it, which is
// what makes a painted body read as a car's; sides facing the camera from above mirror the darker ground.
const float CLEARCOAT_F0 = 0.04;
// Asphalt's albedo, 0.05 fresh to 0.10-0.18 aged (Pomerantz et al., "Cooler paving materials", LBNL-49283,
// 2002); 0.15 for a mix of road and pavement.
const float CLEARCOAT_GROUND_ALBEDO = 0.15;

// The sky's radiance along `r` (at the horizon for a ray below it): the CIE sky's map where the scene has one
// (its texel rows and columns centred on the elevations and azimuths they hold: `SkyMap`), else uniform.
vec3 sky_along(vec3 r)
{
    if (sky_map_used == 0) {
        return ambient_light;
    }
    float elevation = asin(clamp(r.z, 0.0, 1.0));
    // atan(0, 0) is undefined in GLSL: straight up, every azimuth is the zenith
    float azimuth = (abs(r.x) + abs(r.y) > 0.0) ? atan(r.y, r.x) : 0.0;
    return texture(sky_map, vec2(azimuth / (2.0 * PI) + 0.5, elevation / (0.5 * PI))).rgb;
}

// The environment a smooth dielectric mirrors along the reflected ray `r`: the sky's radiance above the
// horizon, the lit ground's below (see clearcoat_ambient).
vec3 mirrored_environment(vec3 r)
{
    float sky_share = clamp(0.5 + 2.5 * r.z, 0.0, 1.0);
    vec3 ground_irradiance = PI * ambient_light;
    for (int i = 0; i < n_directional_lights; i++) {
        ground_irradiance += directional_lights[i].intensity * directional_lights[i].color
            * max(-directional_lights[i].direction.z, 0.0);
    }
    vec3 ground = CLEARCOAT_GROUND_ALBEDO * ground_irradiance / PI;
    return mix(ground, sky_along(r), sky_share);
}

vec3 clearcoat_ambient(vec3 n, vec3 diffuse_ambient)
{
    vec3 v = normalize(cam_pos - frag_position);
    float f_coat = CLEARCOAT_F0 + (1.0 - CLEARCOAT_F0) * pow(1.0 - clamp(dot(n, v), 0.0, 1.0), 5.0);
    return (1.0 - f_coat) * diffuse_ambient + f_coat * mirrored_environment(reflect(-v, n));
}

///////////////////////////////////////////////////////////////////////////////
// MAIN
///////////////////////////////////////////////////////////////////////////////
void main()
{

    vec4 color = vec4(vec3(0.0), 1.0);
///////////////////////////////////////////////////////////////////////////////
// Handle Metallic Materials
///////////////////////////////////////////////////////////////////////////////
#ifdef USE_METALLIC_MATERIAL

    // Compute metallic/roughness factors
    float roughness = material.roughness_factor;
    float metallic = material.metallic_factor;
#ifdef HAS_METALLIC_ROUGHNESS_TEX
    // glTF 2.0 (3.9.2): roughness in the G channel, metalness in B. pyrender's shader reads R and G,
    // which made every textured surface a polished metal (R = 0, G = roughness ≈ 0.9 as metalness).
    vec2 mr = texture(material.metallic_roughness_texture, uv_0, texture_lod_bias).gb;
    roughness = roughness * mr.r;
    metallic = metallic * mr.g;
#endif
    roughness = clamp(roughness, min_roughness, 1.0);
    metallic = clamp(metallic, 0.0, 1.0);
    // In convention, material roughness is perceputal roughness ^ 2
    float alpha_roughness = roughness * roughness;

    // Compute albedo
    vec4 base_color = material.base_color_factor;
#ifdef HAS_BASE_COLOR_TEX
    base_color = base_color * srgb_to_linear(texture(material.base_color_texture, uv_0, texture_lod_bias));
#endif
#ifdef COLOR_0_LOC
    base_color *= color_multiplier;  // glTF 2.0: COLOR_0 multiplies the base colour (albedo), not the light
#endif

    // Compute specular and diffuse colors
    vec3 dialectric_spec = vec3(min_roughness);
    vec3 c_diff = base_color.rgb * (1.0 - metallic);
    vec3 f0 = mix(dialectric_spec, base_color.rgb, metallic);

    // Compute normal
    vec3 n = normalize(get_normal());
#ifdef SPOT_LIGHT_SHADOWS
    // The face's geometric normal (the plane the shadow maps hold), for the spot lights' depth bias; taken
    // here, outside the light loop's per-fragment branches, where derivatives are defined.
    vec3 face_normal = cross(dFdx(frag_position), dFdy(frag_position));
    face_normal = dot(face_normal, face_normal) > 0.0 ? normalize(face_normal) : n;
#endif

    // Loop over lights. camgen: a kind of light the scene has none of is left out of the program
    // (NO_SUNS, NO_POINT_LIGHTS, NO_SPOT_LIGHTS: `_LinearProgramCache`): an empty loop still cost llvmpipe
    // 12 % of a sunlit draw of the parking lot, which has neither point nor spot lights.
#ifndef NO_SUNS
    for (int i = 0; i < n_directional_lights; i++) {
        vec3 direction = directional_lights[i].direction;
        vec3 v = normalize(cam_pos - frag_position); // Vector towards camera
        vec3 l = normalize(-1.0 * direction);   // Vector towards light

        // Compute attenuation and radiance
        float attenuation = directional_lights[i].intensity;
        vec3 radiance = attenuation * directional_lights[i].color;

        // Compute outbound color
        vec3 res = compute_brdf(n, v, l, roughness, metallic,
                                f0, c_diff, base_color.rgb, radiance);

        // Compute shadow
#ifdef DIRECTIONAL_LIGHT_SHADOWS
        float nl = clamp(dot(n,l), 0.0, 1.0);
        // The finest cascade that holds the point; one filtered lookup in its layer. The point's coordinates in
        // each map (orthographic: w is 1), picked by selects rather than a matrix chosen behind branches
        // (llvmpipe runs both sides of a branch whose condition varies across a block of pixels).
        vec4 point = vec4(frag_position, 1.0);
        vec3 ndc_0 = (directional_lights[i].light_matrix * point).xyz;
        vec3 ndc_1 = (directional_lights[i].cascade_matrices[0] * point).xyz;
        vec3 ndc_2 = (directional_lights[i].cascade_matrices[1] * point).xyz;
        bool in_0 = in_sun_cascade(ndc_0.xy, directional_lights[i].shadow_maps);
        bool in_1 = in_sun_cascade(ndc_1.xy, directional_lights[i].shadow_maps);
        vec3 ndc = in_0 ? ndc_0 : (in_1 ? ndc_1 : ndc_2);
        float layer = in_0 ? 0.0 : (in_1 ? 1.0 : 2.0);
        vec2 scales = directional_lights[i].cascade_scales[int(layer)];
        float shadow = shadow_calc_ortho(ndc, directional_lights[i].shadow_maps, layer, scales, nl);
        res = res * (1.0 - shadow);
#endif
        color.xyz += res;
    }
#endif

#ifndef NO_POINT_LIGHTS
    for (int i = 0; i < n_point_lights; i++) {
        vec3 position = point_lights[i].position;
        vec3 v = normalize(cam_pos - frag_position); // Vector towards camera
        vec3 l = normalize(position - frag_position); // Vector towards light

        // Compute attenuation and radiance
        float dist = length(position - frag_position);
        float attenuation = point_lights[i].intensity / (dist * dist);
        vec3 radiance = attenuation * point_lights[i].color;

        // Compute outbound color
        vec3 res = compute_brdf(n, v, l, roughness, metallic,
                                f0, c_diff, base_color.rgb, radiance);
        color.xyz += res;
    }
#endif
#ifndef NO_SPOT_LIGHTS
    for (int i = 0; i < n_spot_lights; i++) {
        vec3 position = spot_lights[i].position;
        vec3 v = normalize(cam_pos - frag_position); // Vector towards camera
        vec3 l = normalize(position - frag_position); // Vector towards light

        // Compute attenuation and radiance
        vec3 direction = spot_lights[i].direction;
        float las = spot_lights[i].light_angle_scale;
        float lao = spot_lights[i].light_angle_offset;
        float dist = length(position - frag_position);
        float cd = clamp(dot(direction, -l), 0.0, 1.0);
        float attenuation = clamp(cd * las + lao, 0.0, 1.0);
        attenuation = attenuation * attenuation;
        if (spot_profile_row[i] > 0) {
            vec3 d = spot_profile_axes[i] * (-l);
            float gamma_deg = degrees(acos(clamp(d.z, -1.0, 1.0)));
            // atan(0, 0) is undefined in GLSL: on the axis (gamma 0 or 180) every C is the same row
            float c_deg = (abs(d.x) + abs(d.y) > 0.0) ? degrees(atan(d.y, d.x)) : 0.0;
            c_deg = c_deg < 0.0 ? c_deg + 360.0 : c_deg;
            ivec2 size = textureSize(spot_profile, 0);
            vec2 uv = vec2((c_deg / 5.0 + 0.5) / float(size.x),
                           (float(spot_profile_row[i] - 1) * 181.0 + gamma_deg + 0.5) / float(size.y));
            attenuation = texture(spot_profile, uv).r;
        }
        if (attenuation <= 0.0) {
            continue;  // outside the beam: no light, and no shadow lookup to divide by zero
        }
        attenuation = attenuation * spot_lights[i].intensity;
        attenuation = attenuation / (dist * dist);
        vec3 radiance = attenuation * spot_lights[i].color;

        // Compute outbound color
        vec3 res = compute_brdf(n, v, l, roughness, metallic,
                                f0, c_diff, base_color.rgb, radiance);
#ifdef SPOT_LIGHT_SHADOWS
        float shadow = shadow_calc_spot(
            spot_lights[i].light_matrix,
            spot_lights[i].shadow_map,
            position,
            face_normal
        );
        res = res * (1.0 - shadow);
#endif
        color.xyz += res;
    }
#endif
#ifdef CLEARCOATED_MATERIAL
    color.xyz += clearcoat_ambient(n, base_color.xyz * ambient_light);
#else
#ifndef TRANSMISSIVE_MATERIAL
    color.xyz += base_color.xyz * ambient_light;
#endif
#endif

    // Calculate lighting from environment
#ifdef USE_IBL
    // TODO
#endif

    // Apply occlusion
#ifdef HAS_OCCLUSION_TEX
    float ao = texture(material.occlusion_texture, uv_0, texture_lod_bias).r;
    color.xyz *= ao;
#endif

    // Apply emissive map
    vec3 emissive = material.emissive_factor;
#ifdef HAS_EMISSIVE_TEX
    emissive *= srgb_to_linear(texture(material.emissive_texture, uv_0, texture_lod_bias)).rgb;
#endif
    color.xyz += emissive;

    // camgen: alpha is coverage. An opaque surface writes 1 whatever its base colour's alpha (glTF 2.0's
    // OPAQUE: the alpha value is ignored); glass blends its alpha as a + (1 - a) * behind (the renderer's
    // glBlendFuncSeparate), so the target's alpha ends as 1 - (the product of the panes' transmittances)
    // over the background and 1 over any surface: Renderer.draw composites the sky and far ground behind.
    float out_alpha = 1.0;
#ifdef TRANSMISSIVE_MATERIAL
    {
        // camgen glass, blended as a * colour + (1 - a) * behind: the reflection R plus the transmitted
        // T (1 - F) of what lies behind, F Schlick's Fresnel reflectance at the view angle. Its ambient
        // reflection is F times the environment along the reflected ray (mirrored_environment, as the
        // paint's clear coat): the sky where the ray goes up (a windscreen or rear window seen from above
        // mirrors the sky, as real ones do), the lit ground where it goes down. The base colour is the
        // glass's own diffuse share (its tint and dirt), lit by the ambient light like any surface.
        vec3 v_glass = normalize(cam_pos - frag_position);
        vec3 n_glass = dot(n, v_glass) < 0.0 ? -n : n;  // the inner panes face into the cabin
        float f_view = CLEARCOAT_F0 + (1.0 - CLEARCOAT_F0) * pow(1.0 - clamp(dot(n_glass, v_glass), 0.0, 1.0), 5.0);
        color.xyz += base_color.xyz * ambient_light + f_view * mirrored_environment(reflect(-v_glass, n_glass));
        out_alpha = 1.0 - (1.0 - base_color.a) * (1.0 - f_view);
        color.xyz /= out_alpha;
    }
#endif
    out_radiance = vec4(color.xyz, out_alpha);
    out_depth_m = vec4(frag_depth_m, 0.0, 0.0, 1.0);
    out_instance_id = instance_id;

#else
    // TODO GLOSSY MATERIAL BRDF
#endif

///////////////////////////////////////////////////////////////////////////////
// Handle Glossy Materials
///////////////////////////////////////////////////////////////////////////////

}
