/* GLSL ES 3.10 sources of the GL renderers (render_gl.c): one source for
 * OpenGL ES 3.1 and, through ARB_ES3_1_compatibility, desktop OpenGL 4.5.
 *
 * Conventions shared with render_gl.c:
 * - primitives live in an RGBA32UI texture, three texels each: (vertex 0,
 *   nverts | rgb << 8), (vertex 1, first | count << 16), (vertex 2, 0), the
 *   words of struct bin_prim rearranged; texel i at (i & (width - 1),
 *   i >> log2 width);
 * - slice coordinates of a point p for image k: s = p . d_k, y, and
 *   t = p . n_k with n_k = (-sin theta_k, 0, cos theta_k);
 * - image k's bow tie is |t| <= |s| tau, tau = tan(pi / N);
 * - where the geometry's brightness model thins anything (brightness.h),
 *   render_gl.c compiles the segment and triangle programs and the pack pass
 *   with BRIGHT defined (the vertex shaders with gl_bright_vs_prelude too),
 *   right after the #version line: the vertex shaders work out the
 *   primitive's weights in the image, the fragment shaders weight its colour
 *   per column, and the pack pass thresholds the band's columns with the
 *   Bresenham pattern. Without it the programs are the exact model's. */
#ifndef SPINDLE_GL_SHADERS_H
#define SPINDLE_GL_SHADERS_H

#define GL_SHADER_VERSION "#version 310 es\n"

/* Uniforms of the drawing programs, set per image:
 * u_image: k (volume image), M (images per volume), 1 = every primitive
 *          (the naive pipeline), log2 of the primitive texture's width;
 * u_slice: cos theta_k, sin theta_k, tau, b (the hyperbolic bias);
 * u_eye:   De (eye distance), T (slab half thickness), jitter x, y (NDC);
 * u_frame: 1 / h, 2 / W, 2 / H, and for the section program which slots
 *          it draws (0 or 1). */
#define GL_SHADER_COMMON                                                                             \
	"precision highp float;\n"                                                                   \
	"precision highp int;\n"                                                                     \
	"precision highp usampler2D;\n"                                                              \
	"uniform uvec4 u_image;\n"                                                                   \
	"uniform vec4 u_slice;\n"                                                                    \
	"uniform vec4 u_eye;\n"                                                                      \
	"uniform vec4 u_frame;\n"                                                                    \
	"uniform usampler2D u_prims;\n"                                                              \
	"const vec4 OFF = vec4(2.0, 2.0, 2.0, 1.0); /* outside the clip volume */\n"                 \
	"uvec4 texel(uint i) {\n"                                                                    \
	"	uint mask = (1u << u_image.w) - 1u;\n"                                                     \
	"	return texelFetch(u_prims, ivec2(int(i & mask), int(i >> u_image.w)), 0);\n"               \
	"}\n"                                                                                        \
	"vec3 syt(uvec4 t) { /* (s, y, t) of the vertex in texel t */\n"                             \
	"	vec3 p = uintBitsToFloat(t.xyz);\n"                                                        \
	"	return vec3(p.x * u_slice.x + p.z * u_slice.y, p.y, p.z * u_slice.x - p.x * u_slice.y);\n" \
	"}\n"                                                                                        \
	"bool in_image(uint w10) { /* the binned range holds image k */\n"                           \
	"	uint first = w10 & 0xffffu, k = u_image.x;\n"                                              \
	"	uint off = k >= first ? k - first : k + u_image.y - first;\n"                              \
	"	return u_image.z != 0u || off < (w10 >> 16);\n"                                            \
	"}\n"                                                                                        \
	"/* Perspective from the eye at De n_k, image plane t = 0, so points on the slice\n"         \
	" * plane map exactly; z spans the slab |t| <= T; jit shifts the sample grid. */\n"          \
	"vec4 project(vec3 syt, vec2 jit) {\n"                                                       \
	"	float de = u_eye.x, t = syt.z, w = de - t;\n"                                              \
	"	return vec4(syt.x * de + jit.x * w, -syt.y * de * u_frame.x + jit.y * w,\n"                \
	"		    (de / u_eye.y) * t - u_eye.y, w);\n"                                                  \
	"}\n"

/* BRIGHT, the vertex shaders' prelude: brightness_weight_of()
 * (brightness.c) of the segment a b or the triangle a b c, in slice
 * coordinates (s, y, t), where the slice plane's normal is the t axis:
 * (kw, inv_cross, 1 where it weighs as a line: a segment, or a triangle of
 * no area, whose rate is line_rate). The edges are scaled to at most 1
 * first, so that float neither overflows nor underflows on them. u_wall.x:
 * the map's wall weight. */
static const char gl_bright_vs_prelude[] =
	"#define BRIGHT 1\n"
	"precision highp float;\n"
	"uniform vec4 u_wall;\n"
	"vec3 weight(vec3 a, vec3 b, vec3 c, bool tri) {\n"
	"	vec3 d = b - a, e = tri ? c - a : vec3(0.0), f = tri ? c - b : vec3(0.0);\n"
	"	vec3 m = max(abs(d), max(abs(e), abs(f)));\n"
	"	float big = max(m.x, max(m.y, m.z));\n"
	"	if (!(big > 0.0))\n"
	"		return vec3(1.0, 1e30, 1.0);\n"
	"	d /= big;\n"
	"	e /= big;\n"
	"	f /= big;\n"
	"	float cr = 0.0;\n"
	"	bool seg = !tri;\n"
	"	if (tri) {\n"
	"		vec3 n = cross(d, e);\n"
	"		float n2 = dot(n, n), l01 = dot(d, d), l02 = dot(e, e), l12 = dot(f, f);\n"
	"		float l = max(l01, max(l02, l12));\n"
	"		if (n2 > 1e-12 * l * l) {\n"
	"			cr = sqrt(dot(n.xy, n.xy) / n2); /* the normal's part in the plane */\n"
	"		} else { /* no area: its longest side */\n"
	"			seg = true;\n"
	"			d = l02 >= l01 && l02 >= l12 ? e : l12 >= l01 ? f : d;\n"
	"		}\n"
	"	}\n"
	"	if (seg) {\n"
	"		float len = length(d);\n"
	"		if (!(len > 0.0))\n"
	"			return vec3(1.0, 1e30, 1.0);\n"
	"		cr = abs(d.z) / len;\n"
	"	}\n"
	"	float wall = sqrt(max(0.0, 1.0 - cr * cr));\n"
	"	return vec3(!seg && wall > u_wall.x ? u_wall.x / wall : 1.0, cr > 1e-20 ? min(1.0 / cr, 1e30) : 1e30,\n"
	"		    seg ? 1.0 : 0.0);\n"
	"}\n";

/* BRIGHT, the fragment shaders' and the pack pass's prelude. */
static const char gl_bright_prelude[] = "#define BRIGHT 1\n";

/* Fragment shaders mark the row of the 32x32 tile their pixel lies in (bit
 * y % 32 of the tile's word), so that only touched rows of touched tiles
 * are packed (and cleared again). u_tile: tiles across, tiles per image,
 * this image's slot in the batch, H. */
#define GL_SHADER_MARK                                                                                       \
	"layout(std430, binding = 2) buffer Touched { uint touched[]; };\n"                                  \
	"uniform uvec4 u_tile;\n"                                                                            \
	"void mark() {\n"                                                                                    \
	"	uvec2 p = uvec2(gl_FragCoord.xy);\n"                                                               \
	"	p.y -= u_tile.z * u_tile.w;\n"                                                                     \
	"	atomicOr(touched[u_tile.z * u_tile.y + (p.y >> 5) * u_tile.x + (p.x >> 5)], 1u << (p.y & 31u));\n" \
	"}\n"

/* BRIGHT: a segment's or triangle's colour c at the fragment's column u,
 * as brightness_apply() weights it: w = min(kw, rate[u] * inv_cross) inside
 * the band (u_band.x .. u_band.y), (kw, inv_cross, line) = v_w from the
 * vertex shader; rate[u] is row 0 of u_bright, or for a line row 1
 * (line_rate; brightness.h, render_gl.c). */
#define GL_SHADER_WEIGH                                                                                   \
	"#ifdef BRIGHT\n"                                                                                 \
	"uniform uvec4 u_band;\n"                                                                         \
	"uniform highp usampler2D u_bright;\n"                                                            \
	"flat in vec3 v_w;\n"                                                                             \
	"uvec3 weigh(uvec3 c) {\n"                                                                        \
	"	uint u = uint(gl_FragCoord.x);\n"                                                               \
	"	if (u < u_band.x || u > u_band.y)\n"                                                            \
	"		return c;\n"                                                                                   \
	"	float rate = uintBitsToFloat(texelFetch(u_bright, ivec2(int(u), v_w.z > 0.5 ? 1 : 0), 0).r);\n" \
	"	float w = min(v_w.x, rate * v_w.y);\n"                                                          \
	"	return w >= 1.0 ? c : uvec3(vec3(c) * w + 1e-3);\n"                                             \
	"}\n"                                                                                             \
	"#endif\n"

/* The fragment's colour v_rgb (weighted with BRIGHT: a fragment that
 * weighs 0 is dropped), its tile row marked. */
#define GL_SHADER_EMIT                                               \
	"flat in uint v_rgb;\n"                                      \
	"out vec4 o_colour;\n"                                       \
	"void emit() {\n"                                            \
	"	uvec3 c = uvec3(v_rgb, v_rgb >> 8, v_rgb >> 16) & 255u;\n" \
	"#ifdef BRIGHT\n"                                            \
	"	c = weigh(c);\n"                                           \
	"	if (c == uvec3(0u))\n"                                     \
	"		discard;\n"                                               \
	"#endif\n"                                                   \
	"	mark();\n"                                                 \
	"	o_colour = vec4(vec3(c) / 255.0, 1.0);\n"                  \
	"}\n"

/* Faces: each triangle drawn whole with the slice's projection; the
 * fragment shader keeps what lies in the bow tie, widened near the axis to
 * the hyperbola t^2 <= (s tau)^2 + b^2 so the thin wedges leave no dead
 * zone. Vertex n is vertex n % 3 of primitive n / 3. */
static const char gl_face_vs[] = GL_SHADER_VERSION GL_SHADER_COMMON
	"out vec2 v_st;\n"
	"flat out uint v_rgb;\n"
	"#ifdef BRIGHT\n"
	"flat out vec3 v_w;\n"
	"#endif\n"
	"void main() {\n"
	"	uint p = uint(gl_VertexID) / 3u, j = uint(gl_VertexID) % 3u;\n"
	"	uvec4 t0 = texel(3u * p), t1 = texel(3u * p + 1u);\n"
	"	v_rgb = t0.w >> 8;\n"
	"	v_st = vec2(0.0);\n"
	"#ifdef BRIGHT\n"
	"	v_w = vec3(1.0, 1.0, 0.0);\n"
	"#endif\n"
	"	gl_Position = OFF;\n"
	"	if ((t0.w & 255u) != 3u || !in_image(t1.w))\n"
	"		return;\n"
	"#ifdef BRIGHT\n"
	"	vec3 a = syt(t0), b = syt(t1), c = syt(texel(3u * p + 2u));\n"
	"	v_w = weight(a, b, c, true);\n"
	"	vec3 q = j == 0u ? a : j == 1u ? b : c;\n"
	"#else\n"
	"	vec3 q = syt(j == 0u ? t0 : j == 1u ? t1 : texel(3u * p + 2u));\n"
	"#endif\n"
	"	v_st = q.xz;\n"
	"	gl_Position = project(q, u_eye.zw);\n"
	"}\n";

static const char gl_face_fs[] = GL_SHADER_VERSION
	"precision highp float;\n"
	"precision highp int;\n" GL_SHADER_MARK GL_SHADER_WEIGH GL_SHADER_EMIT "uniform vec4 u_slice;\n"
	"in vec2 v_st;\n"
	"void main() {\n"
	"	float s = v_st.x * u_slice.z, t = v_st.y;\n"
	"	if (t * t > s * s + u_slice.w * u_slice.w)\n"
	"		discard;\n"
	"	emit();\n"
	"}\n";

/* Sections, drawn as GL_LINES and again as GL_POINTS (so a section shorter
 * than a pixel still lights one): primitive p has 16 vertex slots, up to
 * eight segments of two vertices each, drawn as two draws (slots 0-3, and
 * slots 4-15 where the scene has triangles). A segment primitive is
 * clipped exactly to each lobe (vertices 0-3). A triangle gives its section
 * with the slice plane t = 0 (vertices 0-1), which lights it where it is
 * edge-on to the projection, and its three edges clipped exactly to each
 * lobe (vertices 4-15), which light it where the face pass's sample points
 * miss it: a small or thin triangle inside the wedge that does not reach
 * the slice plane. */
static const char gl_section_vs[] = GL_SHADER_VERSION GL_SHADER_COMMON
	"flat out uint v_rgb;\n"
	"#ifdef BRIGHT\n"
	"flat out vec3 v_w;\n"
	"#endif\n"
	"void main() {\n"
	"	/* u_frame.w: 0 draws slots 0-3 (4 vertices a primitive), 1 the edge\n"
	"	 * slots 4-15 (12 vertices a primitive). */\n"
	"	uint id = uint(gl_VertexID), edges = uint(u_frame.w);\n"
	"	uint p = edges == 0u ? id >> 2 : id / 12u, j = edges == 0u ? id & 3u : id % 12u + 4u;\n"
	"	uvec4 t0 = texel(3u * p), t1 = texel(3u * p + 1u);\n"
	"	bool tri = (t0.w & 255u) == 3u;\n"
	"	v_rgb = t0.w >> 8;\n"
	"	gl_PointSize = 1.0;\n"
	"	gl_Position = OFF;\n"
	"#ifdef BRIGHT\n"
	"	v_w = vec3(1.0, 1.0, 0.0);\n"
	"#endif\n"
	"	if ((tri ? j == 2u || j == 3u : j >= 4u) || !in_image(t1.w))\n"
	"		return;\n"
	"	vec3 a = syt(t0), b = syt(t1);\n"
	"	vec3 c = tri ? syt(texel(3u * p + 2u)) : a;\n"
	"#ifdef BRIGHT\n"
	"	v_w = weight(a, b, c, tri);\n"
	"#endif\n"
	"	if (tri && j < 2u) {\n"
	"		/* The plane is closed: an edge touching it adds its point,\n"
	"		 * an edge lying in it both ends (a mesh edge exactly on the\n"
	"		 * slice plane, e.g. a seam at azimuth 0, is its section). */\n"
	"		vec3 q[6];\n"
	"		vec3 e0[3] = vec3[3](a, b, c), e1[3] = vec3[3](b, c, a);\n"
	"		int n = 0;\n"
	"		for (int i = 0; i < 3; i++) {\n"
	"			vec3 u = e0[i], v = e1[i];\n"
	"			if ((u.z > 0.0 && v.z > 0.0) || (u.z < 0.0 && v.z < 0.0))\n"
	"				continue;\n"
	"			if (u.z == v.z) {\n"
	"				q[n++] = u;\n"
	"				q[n++] = v;\n"
	"			} else {\n"
	"				q[n++] = mix(u, v, u.z / (u.z - v.z));\n"
	"			}\n"
	"		}\n"
	"		if (n == 0)\n"
	"			return;\n"
	"		/* The points are collinear: the ends are the extremes along\n"
	"		 * the axis (s or y) on which they spread most. */\n"
	"		vec2 lo = q[0].xy, hi = q[0].xy;\n"
	"		for (int i = 1; i < n; i++) {\n"
	"			lo = min(lo, q[i].xy);\n"
	"			hi = max(hi, q[i].xy);\n"
	"		}\n"
	"		int axis = hi.x - lo.x >= hi.y - lo.y ? 0 : 1, end = 0;\n"
	"		for (int i = 1; i < n; i++)\n"
	"			if (j == 0u ? q[i][axis] < q[end][axis] : q[i][axis] > q[end][axis])\n"
	"				end = i;\n"
	"		gl_Position = project(vec3(q[end].xy, 0.0), vec2(0.0));\n"
	"		return;\n"
	"	}\n"
	"	if (tri) { /* edge e, clipped like a segment */\n"
	"		uint e = (j - 4u) >> 2;\n"
	"		vec3 v[3] = vec3[3](a, b, c);\n"
	"		a = v[e];\n"
	"		b = v[(e + 1u) % 3u];\n"
	"		j &= 3u;\n"
	"	}\n"
	"	/* Lobe L: t - L tau s <= 0 and -t - L tau s <= 0, for lambda in [0, 1]. */\n"
	"	float L = j < 2u ? 1.0 : -1.0, tau = u_slice.z, lo = 0.0, hi = 1.0;\n"
	"	vec2 g0 = vec2(a.z - L * tau * a.x, -a.z - L * tau * a.x);\n"
	"	vec2 g1 = vec2(b.z - L * tau * b.x, -b.z - L * tau * b.x);\n"
	"	for (int i = 0; i < 2; i++) {\n"
	"		if (g0[i] > 0.0 && g1[i] > 0.0)\n"
	"			return;\n"
	"		if (g0[i] > 0.0)\n"
	"			lo = max(lo, g0[i] / (g0[i] - g1[i]));\n"
	"		else if (g1[i] > 0.0)\n"
	"			hi = min(hi, g0[i] / (g0[i] - g1[i]));\n"
	"	}\n"
	"	if (lo > hi)\n"
	"		return;\n"
	"	gl_Position = project(mix(a, b, (j & 1u) == 0u ? lo : hi), vec2(0.0));\n"
	"}\n";

/* Points arrive reduced by the binning to the voxel (u, v) of this image:
 * attribute x = u | v << 16, y = rgb | size << 24 (struct bin_point). A
 * point lights the pixels whose centres its size x size square holds: the
 * square is centred on the voxel's centre when the size is odd, a quarter
 * pixel past it when even, so that it holds columns u - (size-1)/2 .. u +
 * size/2 (rows likewise), no edge of it lies on a pixel centre (no
 * rasterisation tie) and its centre, which decides whether GL keeps a
 * point at all, stays inside the image. The scissor clips it to the image. */
static const char gl_point_vs[] = GL_SHADER_VERSION
	"precision highp float;\n"
	"precision highp int;\n"
	"uniform vec4 u_frame;\n"
	"layout(location = 0) in uvec2 a_point;\n"
	"flat out uint v_rgb;\n"
	"void main() {\n"
	"	uint size = a_point.y >> 24;\n"
	"	vec2 uv = vec2(uvec2(a_point.x & 0xffffu, a_point.x >> 16)) + ((size & 1u) != 0u ? 0.5 : 0.75);\n"
	"	gl_Position = vec4(uv * u_frame.yz - 1.0, 0.0, 1.0);\n"
	"	gl_PointSize = float(size);\n"
	"	v_rgb = a_point.y & 0xffffffu;\n"
	"}\n";

/* Sections and points; with BRIGHT (the section program only: points are
 * never weighted) the colour is weighted as the face pass weights it. */
static const char gl_flat_fs[] = GL_SHADER_VERSION
	"precision highp float;\n"
	"precision highp int;\n" GL_SHADER_MARK GL_SHADER_WEIGH GL_SHADER_EMIT "void main() {\n"
	"	emit();\n"
	"}\n";

/* The touched tiles of a batch as a list of (tile, row mask), whose header
 * is also the indirect dispatch of the pack pass (groups_x = list length;
 * the CPU sets groups_y = groups_z = 1 and groups_x = 0 first). Clears the
 * marks. u_count: tiles in the batch. */
static const char gl_list_cs[] = GL_SHADER_VERSION
	"precision highp int;\n"
	"layout(local_size_x = 64) in;\n"
	"uniform uint u_count;\n"
	"layout(std430, binding = 2) buffer Touched { uint touched[]; };\n"
	"layout(std430, binding = 3) buffer List { uint groups_x, groups_y, groups_z; uvec2 list[]; };\n"
	"void main() {\n"
	"	uint i = gl_GlobalInvocationID.x;\n"
	"	uint rows = i < u_count ? touched[i] : 0u;\n"
	"	if (rows != 0u) {\n"
	"		touched[i] = 0u;\n"
	"		list[atomicAdd(groups_x, 1u)] = uvec2(i, rows);\n"
	"	}\n"
	"}\n";

/* Halftone + pack + find non-empty tiles: one work group per touched tile
 * (from the list), one invocation per tile row; untouched rows are zero. Each row becomes three
 * words (R, G, B; pixel x of the row at bit x ^ 7, so the little-endian
 * bytes read MSB = leftmost) and is zeroed in the atlas for the next batch;
 * a tile with any bit set takes the next slot of the output (atomic
 * counter) and records its number (slot in batch * tiles per image + t).
 * The thresholds are halftone_threshold()'s (halftone.c), bayer16 and the
 * phase 97 k included: keep the two the same. With BRIGHT, columns
 * u_band.x .. u_band.y take brightness_threshold()'s Bresenham pattern
 * instead: x = (k n[u] + phase[i 16 + v % 16]) % M, threshold 255 x / M,
 * i the column's radius index, so c is lit iff c M > 255 x (u_band.z = M).
 * n[u] and then phase[] are the storage buffer Bright (bound to binding 2
 * while the pass runs); a work group of the band first gathers its 32
 * columns' k n[u] % M in shared memory, a column an invocation.
 * u_pack: first volume image of the batch, W, H, tiles per image. */
static const char gl_pack_cs[] = GL_SHADER_VERSION
	"precision highp float;\n"
	"precision highp int;\n"
	"layout(local_size_x = 32) in;\n"
	"uniform highp sampler2D u_colour;\n"
	"layout(rgba8, binding = 0) writeonly uniform highp image2D u_atlas;\n"
	"uniform uvec4 u_pack;\n"
	"layout(std430, binding = 0) writeonly buffer Tiles { uint tiles[]; };\n"
	"layout(std430, binding = 1) buffer Ids { uint count; uint ids[]; };\n"
	"layout(std430, binding = 3) readonly buffer List { uint groups_x, groups_y, groups_z; uvec2 list[]; };\n"
	"#ifdef BRIGHT\n"
	"uniform uvec4 u_band;\n"
	"layout(std430, binding = 2) readonly buffer Bright { uint bright[]; }; /* n[W], phase[] */\n"
	"shared uint kn[32]; /* k n[u] % M of the tile's columns */\n"
	"#endif\n"
	"shared uint any_bits;\n"
	"shared uint slot;\n"
	"uint bayer16(uint x, uint y) {\n"
	"	uint a = (x ^ y) & 15u, b = y & 15u, v = 0u;\n"
	"	for (uint i = 0u; i < 4u; i++) {\n"
	"		v |= ((a >> i) & 1u) << (7u - 2u * i);\n"
	"		v |= ((b >> i) & 1u) << (6u - 2u * i);\n"
	"	}\n"
	"	return v;\n"
	"}\n"
	"void main() {\n"
	"	uvec2 entry = list[gl_WorkGroupID.x];\n"
	"	uint id = entry.x, tiles_x = (u_pack.y + 31u) >> 5;\n"
	"	uint b = id / u_pack.w, t = id % u_pack.w, tx = t % tiles_x, ty = t / tiles_x;\n"
	"	uint r = gl_LocalInvocationID.x, k = u_pack.x + b, phase = (k * 97u) & 255u;\n"
	"	uint v = ty * 32u + r;\n"
	"	if (r == 0u)\n"
	"		any_bits = 0u;\n"
	"#ifdef BRIGHT\n"
	"	uint u0 = tx * 32u, n = min(32u, u_pack.y - u0), M = u_band.z;\n"
	"	uint hw = u_pack.y / 2u, lw = (u_pack.y - 1u) / 2u;\n"
	"	bool band = u0 + n > u_band.x && u0 <= u_band.y;\n"
	"	if (band && r < n)\n"
	"		kn[r] = k * bright[u0 + r] % M;\n"
	"#endif\n"
	"	memoryBarrierShared();\n"
	"	barrier();\n"
	"	uvec3 bits = uvec3(0u);\n"
	"	if (v < u_pack.z && ((entry.y >> r) & 1u) != 0u) {\n"
	"		uint thr[16];\n"
	"		for (uint i = 0u; i < 16u; i++)\n"
	"			thr[i] = (bayer16(i, (v + (phase >> 4)) & 15u) * 255u) >> 8;\n"
	"		int row = int(b * u_pack.z + v);\n"
	"#ifdef BRIGHT\n"
	"		if (band) {\n"
	"			for (uint x = 0u; x < n; x++) {\n"
	"				uint u = u0 + x;\n"
	"				ivec2 at = ivec2(int(u), row);\n"
	"				uvec3 c = uvec3(texelFetch(u_colour, at, 0).rgb * 255.0 + 0.5);\n"
	"				imageStore(u_atlas, at, vec4(0.0));\n"
	"				uint th = thr[(u + phase) & 15u], bit = 1u << (x ^ 7u);\n"
	"				if (u >= u_band.x && u <= u_band.y) { /* c > 255 x / M */\n"
	"					uint i = 2u * u >= u_pack.y ? u - hw : lw - u; /* radius index */\n"
	"					uint xv = kn[x] + bright[u_pack.y + i * 16u + (v & 15u)];\n"
	"					c *= M;\n"
	"					th = 255u * (xv >= M ? xv - M : xv);\n"
	"				}\n"
	"				bits.r |= c.r > th ? bit : 0u;\n"
	"				bits.g |= c.g > th ? bit : 0u;\n"
	"				bits.b |= c.b > th ? bit : 0u;\n"
	"			}\n"
	"		} else\n"
	"#else\n"
	"		uint n = min(32u, u_pack.y - tx * 32u);\n"
	"#endif\n"
	"		for (uint x = 0u; x < n; x++) {\n"
	"			ivec2 at = ivec2(int(tx * 32u + x), row);\n"
	"			uvec3 c = uvec3(texelFetch(u_colour, at, 0).rgb * 255.0 + 0.5);\n"
	"			imageStore(u_atlas, at, vec4(0.0));\n"
	"			uint th = thr[(tx * 32u + x + phase) & 15u], bit = 1u << (x ^ 7u);\n"
	"			bits.r |= c.r > th ? bit : 0u;\n"
	"			bits.g |= c.g > th ? bit : 0u;\n"
	"			bits.b |= c.b > th ? bit : 0u;\n"
	"		}\n"
	"	}\n"
	"	atomicOr(any_bits, bits.r | bits.g | bits.b);\n"
	"	memoryBarrierShared();\n"
	"	barrier();\n"
	"	if (r == 0u)\n"
	"		slot = any_bits != 0u ? atomicAdd(count, 1u) : 0xffffffffu;\n"
	"	memoryBarrierShared();\n"
	"	barrier();\n"
	"	uint s = slot;\n"
	"	if (s == 0xffffffffu)\n"
	"		return;\n"
	"	tiles[s * 96u + r] = bits.r;\n"
	"	tiles[s * 96u + 32u + r] = bits.g;\n"
	"	tiles[s * 96u + 64u + r] = bits.b;\n"
	"	if (r == 0u)\n"
	"		ids[s] = id;\n"
	"}\n";

/* Grids (scene.h, SCENE_GRID; gl_grid.c): per image and grid draw one
 * quad over the pixels whose centres may lie in the grid's box, u_rect in
 * normalised device coordinates (x0, y0, x1, y1), drawn as a triangle
 * strip of 4 vertices. With BRIGHT the colour is weighted as a surface
 * crossing the slices at right angles: (kw, inv_cross, line) = (wall, 1,
 * 0), so w = min(wall, rate[u]), what grid.c's light() gives. */
static const char gl_grid_vs[] = GL_SHADER_VERSION
	"precision highp float;\n"
	"precision highp int;\n"
	"uniform vec4 u_rect;\n"
	"#ifdef BRIGHT\n"
	"flat out vec3 v_w;\n"
	"#endif\n"
	"void main() {\n"
	"	int i = gl_VertexID;\n"
	"	gl_Position = vec4((i & 1) != 0 ? u_rect.z : u_rect.x, (i & 2) != 0 ? u_rect.w : u_rect.y, 0.0, 1.0);\n"
	"#ifdef BRIGHT\n"
	"	v_w = vec3(u_wall.x, 1.0, 0.0);\n"
	"#endif\n"
	"}\n";

/* The grid's sample at the pixel centre, as grid.c samples it: the pixel
 * (u, v) of the image is the plane point s = (u + 0.5) 2 / W - 1, y = h -
 * (v + 0.5) 2 h / H, in voxel coordinates f = (off + y up) + s dir; dark
 * outside the box -0.5 <= f < n - 0.5; nearest (floor(f + 0.5), clamped)
 * or trilinear (the 8 samples around f, edge samples repeated, mixed in
 * grid.c's order); then the transfer: dark below the threshold (or not a
 * number: a trilinear mix with a NaN sample, or an infinite one weighing
 * 0, is NaN), g = clamp((v - lo) / (hi - lo)), the colour lut[round(g
 * (count - 1))] or rgb g rounded; RGBA8: rgb alpha / 255 with the alpha as
 * the value. Black is dark. The fragments do not mark their tile rows:
 * render_gl.c marks the quads' rows before the batch (gl_grid_mark()).
 * The samples are an unsigned integer 3-D texture of n[1] x n[0] x n[2]
 * texels (j, the grid's up axis, fastest: its memory layout as it is):
 * R8UI (u8), R16UI (u16, and i16 sign-extended here), R32UI (f32 as bits,
 * so a NaN is seen as one whatever the GPU does with it), RGBA8UI (RGBA8).
 * Lookup tables: entry e of the volume's tables at (e % 64, e / 64) of an
 * RGBA8UI texture.
 * u_goff: off, 2 / W; u_gdir: dir, 2 h / H; u_gup: up, h (volume image
 * k's d_k and e_y through the inverse transform, grid.h);
 * u_gn: n[0], n[1], n[2], type (scene_grid_type); u_gtf: threshold, lo,
 * hi, 1 for trilinear; u_gcol: r, g, b, lut entries (0: none); u_glut:
 * the first entry of the draw's table. */
static const char gl_grid_fs[] = GL_SHADER_VERSION
	"precision highp float;\n"
	"precision highp int;\n" GL_SHADER_MARK GL_SHADER_WEIGH "uniform highp usampler3D u_grid;\n"
	"uniform highp usampler2D u_lut;\n"
	"uniform vec4 u_goff, u_gdir, u_gup, u_gtf;\n"
	"uniform uvec4 u_gn, u_gcol;\n"
	"uniform uint u_glut;\n"
	"out vec4 o_colour;\n"
	"/* Sample at (i, j, k): its value (RGBA8: its alpha) and, RGBA8, its\n"
	" * colour; cls 1 for NaN, 2 for an infinity (f32). */\n"
	"float fetch(ivec3 at, out vec4 rgba, out uint cls) {\n"
	"	uvec4 t = texelFetch(u_grid, at.yxz, 0);\n"
	"	rgba = vec4(t);\n"
	"	cls = 0u;\n"
	"	if (u_gn.w == 3u)\n"
	"		return float(int(t.r << 16) >> 16);\n"
	"	if (u_gn.w == 4u) {\n"
	"		if ((t.r & 0x7f800000u) == 0x7f800000u)\n"
	"			cls = (t.r & 0x7fffffu) != 0u ? 1u : 2u;\n"
	"		return uintBitsToFloat(t.r);\n"
	"	}\n"
	"	return float(u_gn.w == 5u ? t.a : t.r);\n"
	"}\n"
	"void main() {\n"
	"	uvec2 px = uvec2(gl_FragCoord.xy);\n"
	"	float s = (float(px.x) + 0.5) * u_goff.w - 1.0;\n"
	"	float y = u_gup.w - (float(px.y - u_tile.z * u_tile.w) + 0.5) * u_gdir.w;\n"
	"	vec3 f = (u_goff.xyz + y * u_gup.xyz) + s * u_gdir.xyz;\n"
	"	vec3 n = vec3(u_gn.xyz);\n"
	"	if (any(lessThan(f, vec3(-0.5))) || any(greaterThanEqual(f, n - 0.5)))\n"
	"		discard;\n"
	"	ivec3 top = ivec3(u_gn.xyz) - 1;\n"
	"	float val = 0.0;\n"
	"	vec4 rgba = vec4(0.0);\n"
	"	bool dark = false;\n"
	"	if (u_gtf.w == 0.0) {\n"
	"		uint cls;\n"
	"		val = fetch(clamp(ivec3(floor(f + 0.5)), ivec3(0), top), rgba, cls);\n"
	"		dark = cls == 1u;\n"
	"	} else {\n"
	"		vec3 fl = floor(f), t = f - fl;\n"
	"		ivec3 i0 = ivec3(fl);\n"
	"		bool pinf = false, ninf = false;\n"
	"		for (int c = 0; c < 8; c++) {\n"
	"			ivec3 b = ivec3(c & 1, (c >> 1) & 1, c >> 2);\n"
	"			float w = 1.0;\n"
	"			w *= b.x != 0 ? t.x : 1.0 - t.x;\n"
	"			w *= b.y != 0 ? t.y : 1.0 - t.y;\n"
	"			w *= b.z != 0 ? t.z : 1.0 - t.z;\n"
	"			vec4 c4;\n"
	"			uint cls;\n"
	"			float x = fetch(clamp(i0 + b, ivec3(0), top), c4, cls);\n"
	"			if (cls == 1u || (cls == 2u && w == 0.0))\n"
	"				dark = true;\n"
	"			else if (cls == 2u && x > 0.0)\n"
	"				pinf = true;\n"
	"			else if (cls == 2u)\n"
	"				ninf = true;\n"
	"			val += w * x;\n"
	"			rgba += w * c4;\n"
	"		}\n"
	"		dark = dark || (pinf && ninf);\n"
	"	}\n"
	"	if (dark || !(val >= u_gtf.x))\n"
	"		discard;\n"
	"	uvec3 c;\n"
	"	if (u_gn.w == 5u) {\n"
	"		c = uvec3(rgba.rgb * rgba.a / 255.0 + 0.5);\n"
	"	} else {\n"
	"		float g = (val - u_gtf.y) / (u_gtf.z - u_gtf.y);\n"
	"		g = g > 0.0 ? (g < 1.0 ? g : 1.0) : 0.0;\n"
	"		if (u_gcol.w != 0u) {\n"
	"			uint e = u_glut + uint(g * float(u_gcol.w - 1u) + 0.5);\n"
	"			c = texelFetch(u_lut, ivec2(int(e & 63u), int(e >> 6)), 0).rgb;\n"
	"		} else {\n"
	"			c = uvec3(vec3(u_gcol.rgb) * g + 0.5);\n"
	"		}\n"
	"	}\n"
	"#ifdef BRIGHT\n"
	"	c = weigh(c);\n"
	"#endif\n"
	"	if (c == uvec3(0u))\n"
	"		discard;\n"

	"	o_colour = vec4(vec3(c) / 255.0, 1.0);\n"
	"}\n";

#endif
