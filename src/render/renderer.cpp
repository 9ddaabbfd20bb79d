// Offscreen rendering: an EGL context without a window (Mesa's surfaceless platform), a
// multisampled framebuffer, flat-shaded two-sided lighting, optional lines on top, read back.

#include <tetcut/error.hpp>
#include <tetcut/render.hpp>

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>

#include "util/broken.hpp"
#include "util/union_find.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

namespace tetcut::render {
namespace {

// The camera. The vertical (or, for a tall picture, horizontal) field of view, in degrees.
constexpr double kFieldOfViewDegrees = 30;
// A scene of one point still has a size to frame (any positive radius frames it alike).
constexpr double kMinRadius = 1e-12;
// A zoom of zero would put the eye at infinity; the CLI and scenes refuse it, this keeps the
// library's own arithmetic finite.
constexpr double kMinZoom = 1e-6;
// The near plane is at least this share of the eye's distance: zoomed inside the scene's sphere,
// the depth buffer keeps 24 bits over a range of at most 1000 : 1.
constexpr double kMinNearShare = 1e-3;

using Mat4 = Eigen::Matrix4f;
using Vec3f = Eigen::Vector3f;

[[noreturn]] void unsupported(const std::string& what) {
  throw Error(ErrorKind::kUnsupported, "offscreen rendering: " + what +
                                           " (it needs Mesa's EGL and OpenGL ES 3: Debian packages libegl-mesa0, "
                                           "libgl1-mesa-dri)");
}

// An EGL display and OpenGL ES 3 context, current for the object's life.
class Context {
 public:
  Context() {
    const auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_display == nullptr) unsupported("EGL lacks eglGetPlatformDisplayEXT");
    display_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, &major, &minor)) unsupported("no surfaceless EGL display");
    if (!eglBindAPI(EGL_OPENGL_ES_API)) unsupported("EGL cannot bind OpenGL ES");
    const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint count = 0;
    eglChooseConfig(display_, config_attributes, &config, 1, &count);
    const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_NONE};
    context_ = eglCreateContext(display_, count > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attributes);
    if (context_ == EGL_NO_CONTEXT) unsupported("no OpenGL ES 3 context");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) unsupported("cannot make the context current");
  }
  ~Context() {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

constexpr const char* kVertexShader = R"(#version 300 es
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 colour;
uniform mat4 projection;
uniform mat4 view;
out vec3 v_normal;
out vec3 v_colour;
out vec3 v_position;
void main() {
  vec4 p = view * vec4(position, 1.0);
  gl_Position = projection * p;
  v_normal = mat3(view) * normal;
  v_colour = colour;
  v_position = p.xyz;
}
)";

// Two-sided: a normal facing away from the eye is turned round, so cut surfaces seen from inside
// and open sheets are lit alike. A key light, a fill light and ambient, in eye space.
constexpr const char* kFragmentShader = R"(#version 300 es
precision highp float;
in vec3 v_normal;
in vec3 v_colour;
in vec3 v_position;
uniform float lit;
out vec4 fragment;
void main() {
  if (lit < 0.5) {
    fragment = vec4(v_colour, 1.0);
    return;
  }
  vec3 n = normalize(v_normal);
  vec3 to_eye = normalize(-v_position);
  if (dot(n, to_eye) < 0.0) n = -n;
  vec3 key = normalize(vec3(0.5, 0.7, 1.0));
  vec3 fill = normalize(vec3(-0.7, -0.3, 0.6));
  float diffuse = 0.65 * max(dot(n, key), 0.0) + 0.2 * max(dot(n, fill), 0.0) + 0.22;
  float specular = 0.2 * pow(max(dot(n, normalize(key + to_eye)), 0.0), 32.0);
  fragment = vec4(min(v_colour * diffuse + vec3(specular), vec3(1.0)), 1.0);
}
)";

GLuint compile(GLenum kind, const char* source) {
  const GLuint shader = glCreateShader(kind);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024];
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    broken("render", std::string("shader does not compile: ") + log);
  }
  return shader;
}

Mat4 look_at(const Vec3f& eye, const Vec3f& target, const Vec3f& up) {
  const Vec3f f = (target - eye).normalized();
  const Vec3f s = f.cross(up).normalized();
  const Vec3f u = s.cross(f);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Mat4 perspective(float fov_y, float aspect, float near, float far) {
  const float t = 1.0f / std::tan(fov_y / 2);
  Mat4 m = Mat4::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (far + near) / (near - far);
  m(2, 3) = 2 * far * near / (near - far);
  m(3, 2) = -1;
  return m;
}

// Interleaved vertices: position, normal, colour.
struct Vertex {
  float data[9];
};

void upload(const std::vector<Vertex>& vertices) {
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)), vertices.data(), GL_STATIC_DRAW);
  for (GLuint a = 0; a < 3; ++a) {
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<const void*>(a * 3 * sizeof(float)));
  }
}

}  // namespace

std::vector<Index> surface_pieces(const TriangleSurface& surface) {
  UnionFind classes(static_cast<std::size_t>(surface.num_vertices()));
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    for (int k = 1; k < 3; ++k) classes.join(surface.triangles(t, 0), surface.triangles(t, k));
  }
  std::vector<Index> number(static_cast<std::size_t>(surface.num_vertices()), -1), pieces(static_cast<std::size_t>(surface.num_triangles()));
  Index count = 0;
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    Index& n = number[classes.find(surface.triangles(t, 0))];
    if (n < 0) n = count++;
    pieces[t] = n;
  }
  return pieces;
}

std::array<std::uint8_t, 3> piece_colour(Index piece) {
  // Hues a golden angle apart, at two levels of saturation so that neighbours differ.
  const double hue = std::fmod(0.08 + 0.618033988749895 * piece, 1.0) * 6;
  const double saturation = piece % 2 == 0 ? 0.55 : 0.4, value = 0.92;
  const int sector = static_cast<int>(hue) % 6;
  const double f = hue - std::floor(hue), p = value * (1 - saturation), q = value * (1 - saturation * f),
               t = value * (1 - saturation * (1 - f));
  double r = 0, g = 0, b = 0;
  switch (sector) {
    case 0: r = value, g = t, b = p; break;
    case 1: r = q, g = value, b = p; break;
    case 2: r = p, g = value, b = t; break;
    case 3: r = p, g = q, b = value; break;
    case 4: r = t, g = p, b = value; break;
    default: r = value, g = p, b = q; break;
  }
  const auto byte = [](double x) { return static_cast<std::uint8_t>(std::lround(255 * x)); };
  return {byte(r), byte(g), byte(b)};
}

Edges mesh_edges(const TetMesh& mesh) { return mesh.adjacency().edges; }

Image render(const TriangleSurface& surface, const RenderOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384) {
    throw Error(ErrorKind::kInvalidArgument, "image size must be from 1 to 16384 pixels each way");
  }
  // The scene's bounding sphere frames the view.
  Eigen::AlignedBox3d box = options.frame;
  if (box.isEmpty()) {
    for (Index v = 0; v < surface.num_vertices(); ++v) box.extend(surface.vertices.row(v).transpose());
    for (Index v = 0; v < options.line_points.rows(); ++v) box.extend(options.line_points.row(v).transpose());
  }
  if (box.isEmpty()) box.extend(Vec3::Zero());
  const Vec3 centre = box.center();
  const double radius = std::max(0.5 * box.diagonal().norm(), kMinRadius);
  const double azimuth = options.camera.azimuth_degrees * std::numbers::pi / 180;
  const double elevation = std::clamp(options.camera.elevation_degrees, -89.0, 89.0) * std::numbers::pi / 180;
  const Vec3 direction(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  const double aspect = static_cast<double>(options.width) / options.height;
  const double fov = kFieldOfViewDegrees * std::numbers::pi / 180;
  const double half_view = std::atan(std::tan(fov / 2) * std::min(aspect, 1.0));  // the narrower half-angle
  const double distance = radius / std::sin(half_view) / std::max(options.camera.zoom, kMinZoom);
  const Vec3 eye = centre + distance * direction;
  const Mat4 view = look_at(eye.cast<float>(), centre.cast<float>(), Vec3f(0, 0, 1));
  const Mat4 projection = perspective(static_cast<float>(fov), static_cast<float>(aspect),
                                      static_cast<float>(std::max(distance - 1.5 * radius, kMinNearShare * distance)),
                                      static_cast<float>(distance + 1.5 * radius));

  Context context;
  GLint max_samples = 1;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  const GLsizei samples = std::clamp(options.samples, 1, static_cast<int>(max_samples));
  GLuint framebuffers[2], renderbuffers[3];
  glGenFramebuffers(2, framebuffers);
  glGenRenderbuffers(3, renderbuffers);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffers[0]);
  glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers[0]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, options.width, options.height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, renderbuffers[0]);
  glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers[1]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, options.width, options.height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, renderbuffers[1]);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) unsupported("the framebuffer is incomplete");

  const GLuint program = glCreateProgram();
  const GLuint vertex_shader = compile(GL_VERTEX_SHADER, kVertexShader), fragment_shader = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  glAttachShader(program, vertex_shader);
  glAttachShader(program, fragment_shader);
  glLinkProgram(program);
  glUseProgram(program);
  glUniformMatrix4fv(glGetUniformLocation(program, "projection"), 1, GL_FALSE, projection.data());
  glUniformMatrix4fv(glGetUniformLocation(program, "view"), 1, GL_FALSE, view.data());
  const GLint lit = glGetUniformLocation(program, "lit");

  glViewport(0, 0, options.width, options.height);
  glClearColor(kBackground[0] / 255.0f, kBackground[1] / 255.0f, kBackground[2] / 255.0f, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  GLuint vertex_array = 0, buffer = 0;
  glGenVertexArrays(1, &vertex_array);
  glBindVertexArray(vertex_array);
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);

  // Triangles, flat shaded: three vertices each with the face's normal and the piece's colour.
  const std::vector<Index> pieces = options.colour_pieces ? surface_pieces(surface) : std::vector<Index>{};
  std::vector<Vertex> vertices;
  vertices.reserve(3 * static_cast<std::size_t>(surface.num_triangles()));
  for (Index t = 0; t < surface.num_triangles(); ++t) {
    const Vec3 a = surface.vertices.row(surface.triangles(t, 0)).transpose(), b = surface.vertices.row(surface.triangles(t, 1)).transpose(),
               c = surface.vertices.row(surface.triangles(t, 2)).transpose();
    Vec3 n = (b - a).cross(c - a);
    n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 1);
    const auto colour = options.colour_pieces ? piece_colour(pieces[t]) : std::array<std::uint8_t, 3>{200, 200, 205};
    for (const Vec3* p : {&a, &b, &c}) {
      vertices.push_back({{static_cast<float>((*p)[0]), static_cast<float>((*p)[1]), static_cast<float>((*p)[2]),
                           static_cast<float>(n[0]), static_cast<float>(n[1]), static_cast<float>(n[2]), colour[0] / 255.0f,
                           colour[1] / 255.0f, colour[2] / 255.0f}});
    }
  }
  if (!vertices.empty()) {
    upload(vertices);
    glUniform1f(lit, 1);
    glEnable(GL_POLYGON_OFFSET_FILL);  // lines drawn later stay in front of the faces they lie on
    glPolygonOffset(1, 1);
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size()));
  }
  if (options.lines.rows() > 0) {
    vertices.clear();
    for (Index e = 0; e < options.lines.rows(); ++e) {
      for (int k = 0; k < 2; ++k) {
        const auto p = options.line_points.row(options.lines(e, k));
        vertices.push_back({{static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]), 0, 0, 1, 0.25f, 0.27f, 0.32f}});
      }
    }
    upload(vertices);
    glUniform1f(lit, 0);
    glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(vertices.size()));
  }

  // Resolve the samples, then read back (OpenGL's rows run bottom-up).
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffers[1]);
  glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers[2]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, options.width, options.height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, renderbuffers[2]);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffers[0]);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffers[1]);
  glBlitFramebuffer(0, 0, options.width, options.height, 0, 0, options.width, options.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffers[1]);
  std::vector<std::uint8_t> rgba(4 * static_cast<std::size_t>(options.width) * options.height);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, options.width, options.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  if (glGetError() != GL_NO_ERROR) unsupported("reading the image back failed");
  Image image;
  image.width = options.width;
  image.height = options.height;
  image.rgb.resize(3 * rgba.size() / 4);
  for (int y = 0; y < options.height; ++y) {
    const std::size_t from_row = static_cast<std::size_t>(options.height - 1 - y) * options.width;
    const std::size_t to_row = static_cast<std::size_t>(y) * options.width;
    for (int x = 0; x < options.width; ++x) {
      for (int k = 0; k < 3; ++k) image.rgb[3 * (to_row + x) + k] = rgba[4 * (from_row + x) + k];
    }
  }
  glDeleteBuffers(1, &buffer);
  glDeleteVertexArrays(1, &vertex_array);
  glDeleteProgram(program);
  glDeleteShader(vertex_shader);
  glDeleteShader(fragment_shader);
  glDeleteRenderbuffers(3, renderbuffers);
  glDeleteFramebuffers(2, framebuffers);
  return image;
}

}  // namespace tetcut::render
