// GLSL 4.50 sources of the renderer's programs. Every program shares the std140 block
// `Frame` (binding 0), filled once per frame from FrameUniforms (renderer.cpp).
#pragma once

// The flow detail's speeds, m/s, as GLSL literals; renderer.cpp checks that they are
// render.h's kFlowDetailMinSpeed and kFlowDetailFullSpeed.
#define MR_FLOW_MIN_SPEED 0.05
#define MR_FLOW_FULL_SPEED 1.5
#define MR_GLSL_STR2(x) #x
#define MR_GLSL_STR(x) MR_GLSL_STR2(x)

namespace mr::render::glsl {

inline constexpr const char* kCommon = R"(#version 450 core
layout(std140, binding = 0) uniform Frame {
    mat4 u_viewproj;
    mat4 u_inv_viewproj;
    vec4 u_eye;        // xyz: camera position
    vec4 u_sun;        // xyz: unit vector towards the sun
    vec4 u_viewport;   // width, height, near, far
    vec4 u_water;      // rgb: deep water colour (linear), a: absorption per metre
    vec4 u_params;     // x: refraction, y: fog on, z: particle radius, w: projection[1][1]
    vec4 u_terrain;    // x: min height, y: max height, z: texture on, w: fog distance
    vec4 u_rect;       // terrain rectangle x0, z0, x1, z1 (texture mapping)
    vec4 u_mode;       // x: water shading (0 realistic, 1 gouraud), y: max tree depth,
                       // z: flow clock (seconds), w: flow detail on
};

const vec3 kSunColor = vec3(1.0, 0.94, 0.84) * 1.15;
const vec3 kHorizon = vec3(0.74, 0.83, 0.92);
const vec3 kZenith = vec3(0.16, 0.36, 0.70);

// The analytic sky: horizon-to-zenith gradient, a sun disc with a glow, and a dim
// haze below the horizon. Used for the background and for the water's reflections.
vec3 sky_color(vec3 d) {
    vec3 c;
    if (d.y >= 0.0) {
        c = mix(kHorizon, kZenith, pow(d.y, 0.5));
    } else {
        // Below the horizon: a bright haze (the terrain is a floating block; what lies
        // beneath it reads as distant lowland mist, not as a grey floor).
        c = mix(kHorizon, vec3(0.80, 0.86, 0.91), min(-d.y * 2.0, 1.0));
    }
    float s = max(dot(d, u_sun.xyz), 0.0);
    c += kSunColor * (pow(s, 1200.0) * 6.0 + pow(s, 24.0) * 0.18);
    return c;
}

vec3 apply_fog(vec3 c, vec3 p) {
    if (u_params.y < 0.5) return c;
    float d = length(p - u_eye.xyz);
    float f = 1.0 - exp(-d / max(u_terrain.w, 1.0));
    return mix(c, kHorizon, f * 0.35);
}

vec3 to_srgb(vec3 c) { return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)); }
vec3 from_srgb(vec3 c) { return pow(c, vec3(2.2)); }
)";

// ---- sky: one full-screen triangle, direction from the inverse view-projection ----
inline constexpr const char* kSkyVert = R"(
out vec2 v_ndc;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    v_ndc = p;
    gl_Position = vec4(p, 1.0, 1.0);
}
)";
inline constexpr const char* kSkyFrag = R"(
in vec2 v_ndc;
out vec4 o_color;
void main() {
    vec4 a = u_inv_viewproj * vec4(v_ndc, -1.0, 1.0);
    vec4 b = u_inv_viewproj * vec4(v_ndc, 1.0, 1.0);
    vec3 d = normalize(b.xyz / b.w - a.xyz / a.w);
    o_color = vec4(to_srgb(sky_color(d)), 1.0);
}
)";

// ---- terrain: height and slope colours, value noise detail, sun + sky light ----
inline constexpr const char* kTerrainVert = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_skirt;
out vec3 v_pos;
out vec3 v_normal;
out float v_skirt;
void main() {
    v_pos = a_pos;
    v_normal = a_normal;
    v_skirt = a_skirt;
    gl_Position = u_viewproj * vec4(a_pos, 1.0);
}
)";
inline constexpr const char* kTerrainFrag = R"(
in vec3 v_pos;
in vec3 v_normal;
in float v_skirt;
layout(binding = 0) uniform sampler2D u_texture;
out vec4 o_color;

float hash(vec2 p) { return fract(sin(dot(p, vec2(127.1, 311.7))) * 43758.5453); }
float vnoise(vec2 p) {
    vec2 i = floor(p), f = fract(p);
    vec2 u = f * f * (3.0 - 2.0 * f);
    return mix(mix(hash(i), hash(i + vec2(1, 0)), u.x), mix(hash(i + vec2(0, 1)), hash(i + vec2(1, 1)), u.x), u.y);
}

void main() {
    vec3 n = normalize(v_normal);
    float range = max(u_terrain.y - u_terrain.x, 1e-3);
    float h = clamp((v_pos.y - u_terrain.x) / range, 0.0, 1.0);
    float slope = 1.0 - clamp(n.y, 0.0, 1.0);
    float detail = vnoise(v_pos.xz * 0.9) * 0.55 + vnoise(v_pos.xz * 3.7) * 0.3 + vnoise(v_pos.xz * 11.0) * 0.15;

    vec3 base;
    if (v_skirt > 0.5) {
        // The cut through the ground at the terrain's edge: earth in strata.
        float band = vnoise(vec2(v_pos.y * 2.5, (v_pos.x + v_pos.z) * 0.15));
        base = mix(vec3(0.26, 0.17, 0.10), vec3(0.42, 0.30, 0.18), band);
        n = normalize(v_normal);
    } else if (u_terrain.z > 0.5) {
        vec2 uv = (v_pos.xz - u_rect.xy) / (u_rect.zw - u_rect.xy);
        base = from_srgb(texture(u_texture, uv).rgb);
    } else {
        vec3 wet = vec3(0.30, 0.25, 0.17);
        vec3 sand = vec3(0.66, 0.56, 0.36);
        vec3 grass = vec3(0.16, 0.34, 0.07);
        vec3 meadow = vec3(0.38, 0.44, 0.13);
        vec3 rock = vec3(0.40, 0.35, 0.30);
        vec3 snow = vec3(0.92, 0.94, 0.97);
        base = mix(wet, sand, smoothstep(0.0, 0.05, h));
        base = mix(base, grass, smoothstep(0.06, 0.16, h + 0.04 * (detail - 0.5)));
        base = mix(base, meadow, smoothstep(0.35, 0.7, h + 0.2 * (detail - 0.5)));
        base = mix(base, rock, smoothstep(0.22, 0.45, slope + 0.12 * (detail - 0.5)));
        base = mix(base, snow, smoothstep(0.88, 0.96, h) * (1.0 - smoothstep(0.3, 0.5, slope)));
        base *= 0.75 + 0.5 * detail;
    }
    float diffuse = max(dot(n, u_sun.xyz), 0.0);
    vec3 hemi = mix(vec3(0.30, 0.26, 0.22), vec3(0.55, 0.65, 0.80), n.y * 0.5 + 0.5);
    vec3 c = base * (kSunColor * diffuse * 1.1 + hemi * 0.45);
    o_color = vec4(to_srgb(apply_fog(c, v_pos)), 1.0);
}
)";

// ---- water: marching-cubes mesh; positions and normals from two buffers ----
inline constexpr const char* kWaterVert = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_velocity;   // the fluid's velocity at the vertex, m/s
out vec3 v_pos;
out vec3 v_normal;
out vec3 v_velocity;
out vec3 v_gouraud;   // per-vertex lighting (the paper's look)
void main() {
    v_pos = a_pos;
    v_normal = a_normal;
    v_velocity = a_velocity;
    vec3 n = normalize(a_normal);
    vec3 v = normalize(u_eye.xyz - a_pos);
    vec3 h = normalize(v + u_sun.xyz);
    float diffuse = max(dot(n, u_sun.xyz), 0.0);
    float spec = pow(max(dot(n, h), 0.0), 48.0);
    vec3 blue = vec3(0.02, 0.16, 0.55);
    v_gouraud = blue * (0.30 + 0.75 * diffuse) + kSunColor * spec * 0.8;
    gl_Position = u_viewproj * vec4(a_pos, 1.0);
}
)";
inline constexpr const char* kWaterFrag = R"(
in vec3 v_pos;
in vec3 v_normal;
in vec3 v_velocity;
in vec3 v_gouraud;
layout(binding = 0) uniform sampler2D u_scene_color;
layout(binding = 1) uniform sampler2D u_scene_depth;
layout(binding = 2) uniform sampler2D u_flow;   // R, G: ripple slopes; B: foam streaks (flow_texture.h)
out vec4 o_color;

// ---- Flow detail (Vlachos, "Water Flow in Portal 2", 2010) ----
// The detail texture is laid in a frame turned to the local flow direction and
// stretched along it (streaks follow the flow), and slides downstream at the flow's
// speed. A layer slid for a whole period would stretch and jump, so two layers half a
// period apart are cross-faded, each weighted 0 when it restarts. The frame is turned
// about the corners of a kFlowCell grid (bilinear blend of the four around the point)
// rather than about the origin, so that a small turn of the flow moves the texture
// by centimetres, not by metres far from the origin.
const float kFlowPeriod = 1.0;                 // seconds per layer cycle (divides 1000)
const vec2 kFlowScale = vec2(1.0 / 7.0, 1.0 / 1.8);  // texture tiles per metre: along, across
const float kFlowCell = 6.0;                   // metres between the frame's pivots
const float kFlowSlope = 0.9;                  // ripple slope at full strength
const float kFlowMinSpeed = )" MR_GLSL_STR(MR_FLOW_MIN_SPEED) R"(;
const float kFlowFullSpeed = )" MR_GLSL_STR(MR_FLOW_FULL_SPEED) R"(;

vec2 pivot_jitter(vec2 c) { return fract(sin(vec2(dot(c, vec2(12.9898, 78.233)), dot(c, vec2(39.346, 11.135)))) * 43758.5453); }

// One layer: the texture in the flow frame, slid `slide` metres downstream.
vec4 flow_layer(vec2 p, vec2 dir, float slide, vec2 offset) {
    vec2 perp = vec2(-dir.y, dir.x);
    vec2 g = p / kFlowCell - 0.5;
    vec2 i = floor(g);
    vec2 f = g - i;
    f = f * f * (3.0 - 2.0 * f);
    vec4 acc = vec4(0.0);
    for (int k = 0; k < 4; ++k) {
        vec2 o = vec2(k & 1, k >> 1);
        vec2 c = (i + o + 0.5) * kFlowCell;
        vec2 d = p - c;
        vec2 q = vec2(dot(d, dir) - slide, dot(d, perp)) * kFlowScale + pivot_jitter(i + o) + offset;
        float w = (o.x > 0.5 ? f.x : 1.0 - f.x) * (o.y > 0.5 ? f.y : 1.0 - f.y);
        acc += w * texture(u_flow, q);
    }
    return acc;
}

// Returns the normal bent by the ripples and, in `foam`, the streaks' share (0 .. 1).
vec3 flow_detail(vec3 n, out float foam) {
    foam = 0.0;
    vec2 v = v_velocity.xz;
    float speed = length(v);
    float strength = smoothstep(kFlowMinSpeed, kFlowFullSpeed, speed);
    if (u_mode.w < 0.5 || strength <= 0.0) return n;
    vec2 dir = v / speed;
    float ph0 = fract(u_mode.z / kFlowPeriod);
    float ph1 = fract(u_mode.z / kFlowPeriod + 0.5);
    vec4 t0 = flow_layer(v_pos.xz, dir, speed * ph0 * kFlowPeriod, vec2(0.0));
    vec4 t1 = flow_layer(v_pos.xz, dir, speed * ph1 * kFlowPeriod, vec2(0.37, 0.61));
    float w1 = abs(1.0 - 2.0 * ph0);   // 1 when layer 0 restarts (ph0 = 0), 0 when layer 1 does
    vec4 t = mix(t0, t1, w1);
    // Slopes in the flow frame (along, across) back to world x/z; the blends above
    // flatten them a little, so they are scaled up again.
    vec2 sl = (t.rg * 2.0 - 1.0) * kFlowSlope * strength * 1.6;
    vec2 slope = sl.x * dir + sl.y * vec2(-dir.y, dir.x);
    foam = strength * smoothstep(0.05, 0.5, t.b) * smoothstep(0.5, 2.0, speed);
    // Only the upward-facing water gets the ripples (not the fronts of drops).
    float up = smoothstep(0.3, 0.7, n.y);
    return normalize(n + up * vec3(-slope.x, 0.0, -slope.y));
}

float linear_depth(float d) {
    float n = u_viewport.z, f = u_viewport.w;
    float z = d * 2.0 - 1.0;
    return 2.0 * n * f / (f + n - z * (f - n));
}

void main() {
    vec2 uv = gl_FragCoord.xy / u_viewport.xy;
    vec3 behind0 = from_srgb(texture(u_scene_color, uv).rgb);
    if (u_mode.x > 0.5) {
        // Gouraud: the lighting was computed per vertex and is interpolated; the
        // surface is a translucent blue over what lies behind it.
        vec3 c = mix(behind0, v_gouraud, 0.8);
        o_color = vec4(to_srgb(apply_fog(c, v_pos)), 1.0);
        return;
    }
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    float streaks = 0.0;
    n = flow_detail(n, streaks);
    vec3 v = normalize(u_eye.xyz - v_pos);
    float wz = linear_depth(gl_FragCoord.z);
    float thick0 = max(linear_depth(texture(u_scene_depth, uv).r) - wz, 0.0);

    // Refraction: shift the lookup by the normal, less where the water is shallow;
    // keep the unshifted lookup when the shifted one lands on something in front.
    vec2 shift = (mat3(u_viewproj) * n).xy * u_params.x * clamp(thick0, 0.0, 1.0);
    vec2 uv2 = uv + shift;
    float tz2 = linear_depth(texture(u_scene_depth, uv2).r);
    if (tz2 < wz) uv2 = uv;
    float thick = max(linear_depth(texture(u_scene_depth, uv2).r) - wz, 0.0);
    vec3 behind = from_srgb(texture(u_scene_color, uv2).rgb);

    // Beer-Lambert over the path through the water: red goes first, then green.
    float k = u_water.a;
    vec3 transmit = exp(-k * thick * vec3(2.2, 0.75, 0.55));
    vec3 refracted = behind * transmit + u_water.rgb * (1.0 - exp(-k * thick * 0.9));

    float cos_t = max(dot(n, v), 0.0);
    float fresnel = 0.02 + 0.98 * pow(1.0 - cos_t, 5.0);
    vec3 reflected = sky_color(reflect(-v, n));
    vec3 c = mix(refracted, reflected, fresnel);

    vec3 h = normalize(v + u_sun.xyz);
    c += kSunColor * (pow(max(dot(n, h), 0.0), 900.0) * 2.5 + pow(max(dot(n, h), 0.0), 90.0) * 0.06);

    // Foam streaks of the flow detail, lit by the sun and the sky.
    c = mix(c, vec3(0.86, 0.90, 0.92) * (0.7 + 0.3 * max(u_sun.y, 0.0)), streaks * 0.75);

    // A soft edge where the water meets the ground, and a little foam at the rim.
    float rim = 1.0 - smoothstep(0.0, 0.25, thick0);
    c = mix(c, vec3(0.85, 0.90, 0.92), rim * 0.35);
    c = mix(behind0, c, smoothstep(0.0, 0.04, thick0));
    o_color = vec4(to_srgb(apply_fog(c, v_pos)), 1.0);
}
)";

// ---- bodies (bodies.h): wood, lit by the sun and the sky; the water is drawn over them ----
// The vertex stage is the terrain's (kTerrainVert: position and normal; no skirt).
inline constexpr const char* kBodyFrag = R"(
in vec3 v_pos;
in vec3 v_normal;
out vec4 o_color;
void main() {
    vec3 n = normalize(gl_FrontFacing ? v_normal : -v_normal);
    // Grain: bands along the body, broken by a slow wave (any orientation reads as wood).
    float grain = 0.5 + 0.5 * sin((v_pos.x + v_pos.z) * 9.0 + sin(v_pos.y * 3.0 + v_pos.x * 0.7) * 2.5);
    vec3 base = mix(vec3(0.30, 0.18, 0.09), vec3(0.48, 0.32, 0.17), grain);
    float sun = max(dot(n, u_sun.xyz), 0.0);
    float sky = 0.5 + 0.5 * n.y;
    vec3 c = base * (kSunColor * sun * 0.8 + vec3(0.60, 0.65, 0.75) * (0.35 + 0.35 * sky));
    o_color = vec4(to_srgb(apply_fog(c, v_pos)), 1.0);
}
)";

// ---- particles (debug): point sprites shaded as spheres ----
inline constexpr const char* kParticleVert = R"(
layout(location = 0) in vec3 a_pos;
void main() {
    gl_Position = u_viewproj * vec4(a_pos, 1.0);
    gl_PointSize = max(2.0, u_params.z * u_params.w * u_viewport.y / max(gl_Position.w, 1e-3));
}
)";
inline constexpr const char* kParticleFrag = R"(
out vec4 o_color;
void main() {
    vec2 q = gl_PointCoord * 2.0 - 1.0;
    float r2 = dot(q, q);
    if (r2 > 1.0) discard;
    vec3 n = vec3(q.x, -q.y, sqrt(1.0 - r2));
    float light = 0.35 + 0.65 * max(dot(n, normalize(vec3(0.4, 0.7, 0.6))), 0.0);
    o_color = vec4(to_srgb(vec3(1.0, 0.45, 0.08) * light), 1.0);
}
)";

// ---- Diffuse particles ([foam]): foam as soft white discs on the water, spray as small
// white points, bubbles as faint blue-white points. a_foam.w is the DiffuseKind (0
// spray, 1 foam, 2 bubble). Foam and bubbles lie about a particle radius under the
// metaball surface (the field's threshold surface encloses the particle centres), so
// they are moved towards the eye by that much: on the water, still hidden by terrain.
inline constexpr const char* kFoamVert = R"(
layout(location = 0) in vec4 a_foam;
out float v_kind;
void main() {
    int kind = int(a_foam.w + 0.5);
    vec3 p = a_foam.xyz;
    float lift = kind == 0 ? 0.0 : (kind == 1 ? 0.6 : 0.35);
    p += normalize(u_eye.xyz - p) * lift;
    float radius = kind == 1 ? 0.35 : 0.12;
    gl_Position = u_viewproj * vec4(p, 1.0);
    gl_PointSize = max(kind == 1 ? 2.5 : 1.5, radius * u_params.w * u_viewport.y / max(gl_Position.w, 1e-3));
    v_kind = float(kind);
}
)";
inline constexpr const char* kFoamFrag = R"(
in float v_kind;
out vec4 o_color;
void main() {
    vec2 q = gl_PointCoord * 2.0 - 1.0;
    float r2 = dot(q, q);
    if (r2 > 1.0) discard;
    int kind = int(v_kind + 0.5);
    vec3 c = kind == 2 ? vec3(0.78, 0.90, 0.95) : vec3(0.97, 0.98, 1.0);
    float a = (kind == 1 ? 0.85 : (kind == 0 ? 0.9 : 0.45)) * (1.0 - r2 * r2);
    float light = 0.75 + 0.25 * max(u_sun.y, 0.0);
    o_color = vec4(to_srgb(c * light), a);
}
)";

// ---- AABB tree boxes (debug): a unit cube's 12 edges, one instance per box ----
inline constexpr const char* kBoxVert = R"(
layout(location = 0) in vec3 a_corner;     // 0 or 1 per axis
layout(location = 1) in vec3 a_min;
layout(location = 2) in vec3 a_max;
layout(location = 3) in float a_depth;
out vec3 v_color;
void main() {
    vec3 p = mix(a_min, a_max, a_corner);
    float t = a_depth / max(u_mode.y, 1.0);
    v_color = mix(vec3(1.0, 0.9, 0.2), vec3(0.9, 0.1, 0.6), t);
    gl_Position = u_viewproj * vec4(p, 1.0);
}
)";
inline constexpr const char* kBoxFrag = R"(
in vec3 v_color;
out vec4 o_color;
void main() { o_color = vec4(v_color, 1.0); }
)";

}  // namespace mr::render::glsl
