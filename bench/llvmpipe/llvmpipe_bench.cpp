// The work of qdmr's benchmarks on Mesa llvmpipe: scenes/plane.json's camera and light, at 1920x1080,
// either its 2-triangle plane or the same plane as a 710x710 grid (1,008,200 triangles). The fragment
// shader does what qdmr's normal-mapping program does: trilinear albedo and normal map (1024², mipmapped),
// tangent-space normal to world, Blinn-Phong with one directional light plus ambient. Colour target:
// RGBA32F (qdmr keeps float colour), depth: 32F. Prints the median of --runs frames (glClear + draw +
// glFinish) after one warm-up frame that compiles the shaders, and the pixels covered (a check
// that the work matches qdmr's pixels_shaded).
//
//   LIBGL_ALWAYS_SOFTWARE=1 LP_NUM_THREADS=2 llvmpipe_bench --mesh grid --runs 7
#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES
#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

constexpr int kWidth = 1920, kHeight = 1080, kTextureSide = 1024;

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

struct Mat4 {
  float m[16] = {};  // column-major
};

Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) r.m[c * 4 + row] += a.m[k * 4 + row] * b.m[c * 4 + k];
  return r;
}

struct Vec3 {
  float x, y, z;
};
Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 normalize(Vec3 a) {
  const float l = std::sqrt(dot(a, a));
  return {a.x / l, a.y / l, a.z / l};
}

// The camera of scenes/plane.json (glm::lookAt and glm::perspective, GL conventions).
Mat4 view_projection(Vec3& eye_out) {
  const Vec3 eye{0, -2.2f, 1.6f}, target{0, 0.2f, 0}, up{0, 0, 1};
  const Vec3 f = normalize(sub(target, eye)), s = normalize(cross(f, up)), u = cross(s, f);
  Mat4 view;
  const float v[16] = {s.x, u.x, -f.x, 0, s.y, u.y, -f.y, 0, s.z, u.z, -f.z, 0, -dot(s, eye), -dot(u, eye), dot(f, eye), 1};
  std::memcpy(view.m, v, sizeof v);
  const float fov = 50.0f * 3.14159265f / 180.0f, aspect = float(kWidth) / kHeight, n = 0.05f, fa = 50.0f;
  const float t = 1.0f / std::tan(fov / 2);
  Mat4 proj;
  proj.m[0] = t / aspect;
  proj.m[5] = t;
  proj.m[10] = -(fa + n) / (fa - n);
  proj.m[11] = -1;
  proj.m[14] = -2 * fa * n / (fa - n);
  eye_out = eye;
  return mul(proj, view);
}

// A 4x4 plane at z = 0 with uv_scale 2, as `resolution`² quads (two triangles each), normal +z, tangent +x.
void make_grid(int resolution, std::vector<float>& vertices, std::vector<std::uint32_t>& indices) {
  const int n = resolution + 1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float u = float(i) / resolution, v = float(j) / resolution;
      vertices.insert(vertices.end(), {-2 + 4 * u, -2 + 4 * v, 0, 2 * u, 2 * v});
    }
  for (int j = 0; j < resolution; ++j)
    for (int i = 0; i < resolution; ++i) {
      const std::uint32_t a = std::uint32_t(j * n + i), b = a + 1, c = a + std::uint32_t(n), d = c + 1;
      indices.insert(indices.end(), {a, b, d, a, d, c});
    }
}

// Bricks-like albedo and a bumpy normal map; the content does not change the cost of trilinear fetches.
GLuint make_texture(bool normal_map) {
  std::vector<std::uint8_t> texels(std::size_t(kTextureSide) * kTextureSide * 4);
  for (int y = 0; y < kTextureSide; ++y)
    for (int x = 0; x < kTextureSide; ++x) {
      std::uint8_t* t = &texels[(std::size_t(y) * kTextureSide + x) * 4];
      const float a = std::sin(float(x) * 0.05f), b = std::cos(float(y) * 0.07f);
      if (normal_map) {
        const Vec3 nrm = normalize({0.4f * a, 0.4f * b, 1.0f});
        t[0] = std::uint8_t(127.5f + 127.5f * nrm.x), t[1] = std::uint8_t(127.5f + 127.5f * nrm.y), t[2] = std::uint8_t(127.5f + 127.5f * nrm.z);
      } else {
        t[0] = std::uint8_t(120 + 60 * a), t[1] = std::uint8_t(70 + 30 * b), t[2] = 50;
      }
      t[3] = 255;
    }
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, kTextureSide, kTextureSide, 0, GL_RGBA, GL_UNSIGNED_BYTE, texels.data());
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  return tex;
}

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;
uniform mat4 view_projection;
out vec3 world;
out vec2 tex;
void main() {
  world = position;
  tex = uv;
  gl_Position = view_projection * vec4(position, 1.0);
}
)";

const char* kFragmentShader = R"(#version 330 core
in vec3 world;
in vec2 tex;
uniform sampler2D albedo_map;
uniform sampler2D normal_map;
uniform vec3 eye;
out vec4 color;
const vec3 N = vec3(0, 0, 1), T = vec3(1, 0, 0), B = vec3(0, 1, 0);
const vec3 light_dir = normalize(vec3(-0.5, -0.4, 0.75));
const vec3 light = vec3(1.0, 0.96, 0.9) * 1.1, ambient = vec3(0.55, 0.65, 0.9) * 0.18;
void main() {
  vec3 albedo = texture(albedo_map, tex).rgb;
  vec3 nt = texture(normal_map, tex).xyz * 2.0 - 1.0;
  vec3 n = normalize(nt.x * T + nt.y * B + nt.z * N);
  vec3 v = normalize(eye - world);
  vec3 h = normalize(light_dir + v);
  float diffuse = max(dot(n, light_dir), 0.0);
  float specular = diffuse > 0.0 ? 0.15 * pow(max(dot(n, h), 0.0), 24.0) : 0.0;
  color = vec4(albedo * (ambient + light * diffuse) + light * specular, 1.0);
}
)";

GLuint compile(GLenum type, const char* source) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    fail(std::string("shader: ") + log);
  }
  return s;
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

int run(int argc, char** argv) {
  std::string mesh = "grid";
  int runs = 7;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mesh" && i + 1 < argc) mesh = argv[++i];
    else if (arg == "--runs" && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else fail("usage: llvmpipe_bench [--mesh grid|plane] [--runs N]");
  }
  if (mesh != "grid" && mesh != "plane") fail("--mesh must be grid or plane");
  make_context();

  GLuint fbo = 0, rb[2] = {};
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glGenRenderbuffers(2, rb);
  glBindRenderbuffer(GL_RENDERBUFFER, rb[0]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, kWidth, kHeight);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
  glBindRenderbuffer(GL_RENDERBUFFER, rb[1]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, kWidth, kHeight);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("framebuffer incomplete");
  glViewport(0, 0, kWidth, kHeight);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_CULL_FACE);

  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;
  make_grid(mesh == "grid" ? 710 : 1, vertices, indices);
  GLuint vao = 0, buffers[2] = {};
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(2, buffers);
  glBindBuffer(GL_ARRAY_BUFFER, buffers[0]);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(vertices.size() * sizeof(float)), vertices.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffers[1]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(indices.size() * sizeof(std::uint32_t)), indices.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 5 * sizeof(float), nullptr);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 5 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);

  const GLuint program = glCreateProgram();
  glAttachShader(program, compile(GL_VERTEX_SHADER, kVertexShader));
  glAttachShader(program, compile(GL_FRAGMENT_SHADER, kFragmentShader));
  glLinkProgram(program);
  glUseProgram(program);
  Vec3 eye{};
  const Mat4 vp = view_projection(eye);
  glUniformMatrix4fv(glGetUniformLocation(program, "view_projection"), 1, GL_FALSE, vp.m);
  glUniform3f(glGetUniformLocation(program, "eye"), eye.x, eye.y, eye.z);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, make_texture(false));
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, make_texture(true));
  glUniform1i(glGetUniformLocation(program, "albedo_map"), 0);
  glUniform1i(glGetUniformLocation(program, "normal_map"), 1);

  std::vector<double> ms;
  for (int i = 0; i <= runs; ++i) {  // frame 0 is the warm-up
    const auto start = std::chrono::steady_clock::now();
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDrawElements(GL_TRIANGLES, GLsizei(indices.size()), GL_UNSIGNED_INT, nullptr);
    glFinish();
    if (i > 0) ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  if (glGetError() != GL_NO_ERROR) fail("a GL call failed");
  std::vector<float> depth(std::size_t(kWidth) * kHeight);
  glReadPixels(0, 0, kWidth, kHeight, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  const auto covered = std::count_if(depth.begin(), depth.end(), [](float d) { return d < 1.0f; });
  std::sort(ms.begin(), ms.end());
  std::printf("{\"renderer\": \"%s\", \"mesh\": \"%s\", \"triangles\": %zu, \"pixels_covered\": %td, \"runs\": %d, "
              "\"median_ms\": %.3f}\n",
              reinterpret_cast<const char*>(glGetString(GL_RENDERER)), mesh.c_str(), indices.size() / 3, covered, runs,
              ms[ms.size() / 2]);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "llvmpipe_bench: %s\n", e.what());
    return 1;
  }
}
