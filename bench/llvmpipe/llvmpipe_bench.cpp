// The work of qdmr's benchmarks on Mesa llvmpipe, through EGL (surfaceless) and OpenGL 3.3 core. Two scenes:
//
//  --mesh grid|plane (the default: --mesh grid): scenes/plane.json's camera and light at 1920x1080, either its
//     2-triangle plane or the same plane as a 710x710 grid (1,008,200 triangles); the fragment shader does what
//     qdmr's normal-mapping program does: trilinear albedo and normal map (1024², synthetic, mipmapped),
//     tangent-space normal to world, Blinn-Phong with one directional light plus ambient.
//
//  --technique normal|pom|relief|qdm --depth D: bench/llvmpipe/canonical.json, the scene of the llvmpipe
//     comparison (bench/llvmpipe_compare.py): its camera, light, the same cobbles height map (canonical.cpp
//     generates the bits qdmr generates, stored as r16 like qdmr stores them) and GLSL versions of qdmr's
//     POM, relief and QDM (src/kernel/pom.hpp, relief.hpp, qdm.hpp, traversal.hpp, refine.hpp) with the
//     scene's knobs (shaders.cpp), then Blinn-Phong shading as qdmr's shade_lights does.
//
// Colour target: RGBA32F (qdmr keeps float colour), depth: 32F. Prints, as one JSON line, the median of --runs
// frames (glClear + draw + glFinish) after one warm-up frame that compiles the shaders, and the pixels covered
// (a check that the work matches qdmr's pixels_shaded). --hit-uv FILE renders one frame of the canonical scene
// writing the UV of the hit and the loop iterations per pixel (a PFM: write_hit_uv below), for the texel check
// of bench/llvmpipe_compare.py; --image FILE writes the last timed frame's colour (PFM) to look at.
//
//   LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe LP_NUM_THREADS=2 llvmpipe_bench --mesh grid --runs 7
//   LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe LP_NUM_THREADS=2 llvmpipe_bench --technique qdm --depth 0.3
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene.hpp"
#include "shaders.hpp"

namespace llvmpipe_bench {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

constexpr const char* kUsage =
    "usage: llvmpipe_bench [--mesh grid|plane] [--technique normal|pom|relief|qdm] [--depth D] [--width W]\n"
    "                      [--height H] [--runs N] [--hit-uv FILE] [--image FILE]\n"
    "  --mesh: plane.json's normal-mapped plane or 710x710 grid (the default: grid; only with --technique normal)\n"
    "  --technique: the canonical scene (bench/llvmpipe/canonical.json) with that technique, depth scale --depth\n"
    "  --hit-uv FILE: one frame of the canonical scene, hit UV and iterations per pixel to FILE (PFM)\n"
    "  --image FILE: the last timed frame's linear colour to FILE (PFM)";

struct Options {
  std::string mesh;       // set: the plane.json scene
  std::string technique;  // set: the canonical scene
  float depth = 0.1f;
  int width = 1920, height = 1080, runs = 7;
  std::string hit_uv;
  std::string image;  // the last timed frame's colour (linear), PFM
};

float to_float(const std::string& s, const char* what) {
  char* end = nullptr;
  const float v = std::strtof(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0') fail(std::string(what) + ": not a number: " + s);
  return v;
}

int to_int(const std::string& s, const char* what, int low, int high) {
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (end == s.c_str() || *end != '\0' || v < low || v > high)
    fail(std::string(what) + " must be an integer in " + std::to_string(low) + ".." + std::to_string(high));
  return int(v);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--help" || arg == "-h") {
      std::puts(kUsage);
      std::exit(0);
    } else if (!has_value) {
      fail(std::string("missing value or unknown option: ") + arg + "\n" + kUsage);
    } else if (arg == "--mesh") {
      o.mesh = argv[++i];
    } else if (arg == "--technique") {
      o.technique = argv[++i];
    } else if (arg == "--depth") {
      o.depth = to_float(argv[++i], "--depth");
    } else if (arg == "--width") {
      o.width = to_int(argv[++i], "--width", 1, 16384);
    } else if (arg == "--height") {
      o.height = to_int(argv[++i], "--height", 1, 16384);
    } else if (arg == "--runs") {
      o.runs = to_int(argv[++i], "--runs", 1, 100000);
    } else if (arg == "--hit-uv") {
      o.hit_uv = argv[++i];
    } else if (arg == "--image") {
      o.image = argv[++i];
    } else {
      fail("unknown option " + arg + "\n" + kUsage);
    }
  }
  // Without --technique and --hit-uv: plane.json's grid, what llvmpipe_bench did before it had techniques.
  if (o.technique.empty() && o.hit_uv.empty() && o.mesh.empty()) o.mesh = "grid";
  if (o.technique.empty()) o.technique = "normal";
  if (!o.mesh.empty()) {
    if (o.mesh != "grid" && o.mesh != "plane") fail("--mesh must be grid or plane");
    if (o.technique != "normal")
      fail("--mesh is plane.json's normal mapping; --technique " + o.technique + " takes no --mesh");
    if (!o.hit_uv.empty()) fail("--hit-uv renders the canonical scene; drop --mesh");
  }
  if (!technique_known(o.technique)) fail("--technique must be normal, pom, relief or qdm");
  if (!(o.depth >= 0.0f && o.depth <= 100.0f)) fail("--depth must be in 0..100");
  return o;
}

void make_context() {
  const auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_platform_display) fail("eglGetPlatformDisplayEXT is missing");
  EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, nullptr, nullptr)) fail("no surfaceless EGL display");
  if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API) failed");
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  eglChooseConfig(display, config_attribs, &config, 1, &configs);
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext context = eglCreateContext(display, configs > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT || !eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context))
    fail("cannot create a GL 3.3 core context");
}

// An FBO with an RGBA32F colour and a 32F depth renderbuffer, bound, with its viewport.
void make_framebuffer(int width, int height) {
  GLuint fbo = 0, rb[2] = {};
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenRenderbuffers(2, rb);
  glBindRenderbuffer(GL_RENDERBUFFER, rb[0]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
  glBindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("framebuffer incomplete");
  glViewport(0, 0, width, height);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_CULL_FACE);
}

// Uploads the mesh (position xyz, uv) into a bound VAO; returns the index count.
GLsizei upload_mesh(const Mesh& mesh) {
  GLuint vao = 0, buffers[2] = {};
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(2, buffers);
  glBindBuffer(GL_ARRAY_BUFFER, buffers[0]);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(mesh.vertices.size() * sizeof(float)), mesh.vertices.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffers[1]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(mesh.indices.size() * sizeof(std::uint32_t)), mesh.indices.data(),
               GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 5 * sizeof(float), nullptr);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 5 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  return GLsizei(mesh.indices.size());
}

GLuint compile(GLenum type, const std::string& source) {
  const GLuint s = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    fail(std::string("shader: ") + log);
  }
  return s;
}

GLuint link_program(const std::string& fragment_source) {
  const GLuint program = glCreateProgram();
  glAttachShader(program, compile(GL_VERTEX_SHADER, vertex_shader()));
  glAttachShader(program, compile(GL_FRAGMENT_SHADER, fragment_source));
  glLinkProgram(program);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    fail(std::string("link: ") + log);
  }
  glUseProgram(program);
  return program;
}

// A 2D texture with the given levels (level i: side >> i), wrap addressing and the filters, created on the
// active texture unit (and left bound to it).
void make_texture(GLenum internal_format, GLenum format, GLenum type, const std::vector<const void*>& levels, int side,
                  GLenum min_filter, GLenum mag_filter, bool generate_mips) {
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const int s = std::max(1, side >> i);
    glTexImage2D(GL_TEXTURE_2D, GLint(i), GLint(internal_format), s, s, 0, format, type, levels[i]);
  }
  if (generate_mips) glGenerateMipmap(GL_TEXTURE_2D);
  else glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, GLint(levels.size()) - 1);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GLint(min_filter));
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GLint(mag_filter));
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
}

// Makes `unit` the active texture unit and points the sampler `name` at it: the next make_texture lands there.
void use_unit(GLuint program, const char* name, int unit) {
  glActiveTexture(GLenum(GL_TEXTURE0 + unit));
  glUniform1i(glGetUniformLocation(program, name), unit);
}

// Albedo (sRGB) and normal map (RGBA8), trilinear as the scenes' "sampling/filter" says; for a displacement
// technique also the heights (R32F, level 0 only, bilinear: the scene's "height_fetch") and their max chain
// (R32F, every level, read with texelFetch).
void bind_textures(GLuint program, const SceneTextures& t, bool displaced) {
  const GLenum trilinear = GL_LINEAR_MIPMAP_LINEAR;
  use_unit(program, "albedo_map", 0);
  make_texture(t.albedo_srgb ? GL_SRGB8_ALPHA8 : GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, {t.albedo.data()}, t.side,
               trilinear, GL_LINEAR, true);
  use_unit(program, "normal_map", 1);
  make_texture(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, {t.normal.data()}, t.side, trilinear, GL_LINEAR, true);
  if (!displaced) return;
  use_unit(program, "height_map", 2);
  make_texture(GL_R32F, GL_RED, GL_FLOAT, {t.max_chain[0].data()}, t.side, GL_LINEAR, GL_LINEAR, false);
  std::vector<const void*> levels;
  for (const auto& level : t.max_chain) levels.push_back(level.data());
  use_unit(program, "max_tree", 3);
  make_texture(GL_R32F, GL_RED, GL_FLOAT, levels, t.side, GL_NEAREST_MIPMAP_NEAREST, GL_NEAREST, false);
}

void draw(GLsizei index_count, const float clear[4]) {
  glClearColor(clear[0], clear[1], clear[2], clear[3]);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDrawElements(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, nullptr);
  glFinish();
}

// Frame 0 is the warm-up (the shader is compiled on the first draw); the others are timed.
std::vector<double> time_frames(GLsizei index_count, int runs, const float background[4]) {
  std::vector<double> ms;
  for (int i = 0; i <= runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    draw(index_count, background);
    if (i > 0) ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  if (glGetError() != GL_NO_ERROR) fail("a GL call failed");
  return ms;
}

long covered_pixels(int width, int height) {
  std::vector<float> depth(std::size_t(width) * std::size_t(height));
  glReadPixels(0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  return long(std::count_if(depth.begin(), depth.end(), [](float d) { return d < 1.0f; }));
}

// The colour target as RGB floats, rows bottom to top (glReadPixels' order).
std::vector<float> read_rgb(int width, int height) {
  std::vector<float> rgba(std::size_t(width) * std::size_t(height) * 4);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, rgba.data());
  if (glGetError() != GL_NO_ERROR) fail("a GL call failed");
  std::vector<float> rgb;
  rgb.reserve(rgba.size() / 4 * 3);
  for (std::size_t i = 0; i < rgba.size(); i += 4) rgb.insert(rgb.end(), {rgba[i], rgba[i + 1], rgba[i + 2]});
  return rgb;
}

// A 3-channel PFM: little-endian floats, rows bottom to top as the format stores them (and GL returns them).
void write_pfm(const std::string& path, int width, int height, const std::vector<float>& rgb) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) fail("cannot write " + path);
  std::fprintf(f, "PF\n%d %d\n-1.0\n", width, height);  // negative scale: little-endian
  const bool ok = std::fwrite(rgb.data(), sizeof(float), rgb.size(), f) == rgb.size();
  if (std::fclose(f) != 0 || !ok) fail("cannot write " + path);
}

// One frame of the hit-UV shader, written as a PFM of three channels: hit u, hit v, loop iterations (-1 where
// no triangle covers the pixel). Returns the mean iterations over the covered pixels.
double write_hit_uv(GLsizei index_count, int width, int height, const std::string& path) {
  const float uncovered[4] = {0, 0, -1, 0};
  draw(index_count, uncovered);
  const std::vector<float> rgb = read_rgb(width, height);
  double iterations = 0;
  long covered = 0;
  for (std::size_t i = 2; i < rgb.size(); i += 3)
    if (rgb[i] >= 0.0f) iterations += rgb[i], ++covered;
  write_pfm(path, width, height, rgb);
  return covered > 0 ? iterations / double(covered) : 0.0;
}

int run(int argc, char** argv) {
  const Options o = parse(argc, argv);
  const bool canonical = o.mesh.empty();
  const Scene scene = canonical ? canonical_scene() : plane_scene();
  const Technique technique = canonical ? canonical_technique(o.technique, o.depth) : Technique{};
  make_context();
  make_framebuffer(o.width, o.height);
  const GLsizei index_count = upload_mesh(make_grid(canonical || o.mesh == "plane" ? 1 : 710));
  const bool hit_uv = !o.hit_uv.empty();
  const GLuint program = link_program(canonical ? fragment_shader(technique, hit_uv) : legacy_fragment_shader());
  const Mat4 vp = view_projection(scene.camera, float(o.width) / float(o.height));
  glUniformMatrix4fv(glGetUniformLocation(program, "view_projection"), 1, GL_FALSE, vp.m);
  glUniform3f(glGetUniformLocation(program, "eye"), scene.camera.eye.x, scene.camera.eye.y, scene.camera.eye.z);
  bind_textures(program, canonical ? canonical_textures() : plane_textures(), technique.kind != TechniqueKind::Normal);

  const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string what = canonical ? "\"scene\": \"canonical\", \"technique\": \"" + o.technique +
                                           "\", \"depth_scale\": " + std::to_string(o.depth) +
                                           ", \"knobs\": " + technique_json(technique)
                                     : "\"scene\": \"plane\", \"mesh\": \"" + o.mesh + "\"";
  if (hit_uv) {
    const double iterations = write_hit_uv(index_count, o.width, o.height, o.hit_uv);
    std::printf("{\"renderer\": \"%s\", %s, \"width\": %d, \"height\": %d, \"pixels_covered\": %ld, "
                "\"iterations_mean\": %.4f, \"hit_uv\": \"%s\"}\n",
                renderer.c_str(), what.c_str(), o.width, o.height, covered_pixels(o.width, o.height), iterations,
                o.hit_uv.c_str());
    return 0;
  }
  std::vector<double> ms = time_frames(index_count, o.runs, scene.background);
  if (!o.image.empty()) write_pfm(o.image, o.width, o.height, read_rgb(o.width, o.height));
  const long covered = covered_pixels(o.width, o.height);
  std::string frames;
  for (double m : ms) frames += (frames.empty() ? "" : ", ") + std::to_string(m);
  std::sort(ms.begin(), ms.end());
  std::printf("{\"renderer\": \"%s\", %s, \"width\": %d, \"height\": %d, \"triangles\": %d, \"pixels_covered\": %ld, "
              "\"runs\": %d, \"median_ms\": %.3f, \"frames_ms\": [%s]}\n",
              renderer.c_str(), what.c_str(), o.width, o.height, index_count / 3, covered, o.runs, ms[ms.size() / 2],
              frames.c_str());
  return 0;
}

}  // namespace
}  // namespace llvmpipe_bench

int main(int argc, char** argv) {
  try {
    return llvmpipe_bench::run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "llvmpipe_bench: %s\n", e.what());
    return 1;
  }
}
