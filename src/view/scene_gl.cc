#include "view/scene_gl.h"

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <cmath>
#include <string>

#include "view/shapes.h"

namespace rigidtouch::view {
namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform mat4 mvp;
uniform mat3 rot;
out vec3 normal_w;
void main() {
  normal_w = rot * normal;
  gl_Position = mvp * vec4(position, 1.0);
}
)";

// diffuse light from one direction over an ambient floor, saturating at the colour itself: a
// pixel is the geom's colour times a factor in [0.45, 1], so the screenshot tests can tell a geom
// by the ratios of its channels. Both sides are lit alike: a mesh's winding does not matter.
constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 normal_w;
uniform vec3 color;
uniform vec3 light;
uniform float lit;
out vec4 frag;
void main() {
  float k = min(1.0, 0.45 + 0.75 * abs(dot(normalize(normal_w), light)));
  frag = vec4(color * mix(1.0, k, lit), 1.0);
}
)";

unsigned Compile(unsigned type, const char* source) {
  const unsigned s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  int ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw Error(std::string("view: the geom shader does not compile: ") + log);
  }
  return s;
}

void AppendLine(std::vector<float>& out, const Vec3& a, const Vec3& b) {
  for (const Vec3& p : {a, b}) {
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(p[k]));
    for (int k = 0; k < 3; ++k) out.push_back(k == 2 ? 1.0f : 0.0f);
  }
}

// a plane's grid of 1 cm cells (5 cm for large scenes), every fifth line thick, over the framed
// scene (an MJCF plane of size 0 is infinite); lines into `thin` or `thick`
void AppendGrid(const GeomModel& g, const SceneFrame& frame, std::vector<float>& thin,
                std::vector<float>& thick) {
  const double half = frame.grid_half_m;
  const double step = half > 0.3 ? 0.05 : 0.01;
  const Mat3 R = g.quat_B.toRotationMatrix();
  const Vec3 local = R.transpose() * (frame.centre - g.pos_B);
  const double hx = g.size.x() > 0.0 ? std::min(g.size.x(), half) : half;
  const double hy = g.size.y() > 0.0 ? std::min(g.size.y(), half) : half;
  const double ox = std::round(local.x() / step) * step, oy = std::round(local.y() / step) * step;
  const auto world = [&](double x, double y) { return Vec3(g.pos_B + R * Vec3(x, y, 0.0)); };
  for (double t = -half; t <= half + 1e-9; t += step) {
    std::vector<float>& out =
        std::abs(std::fmod(std::abs(t + ox) + 1e-9, 5 * step)) < 2e-9 ? thick : thin;
    AppendLine(out, world(ox + t, oy - hy), world(ox + t, oy + hy));
    AppendLine(out, world(ox - hx, oy + t), world(ox + hx, oy + t));
  }
}

}  // namespace

SceneRenderer::SceneRenderer(const Model& model, const SceneFrame& frame) {
  std::vector<float> data, thin, thick;
  for (const GeomModel& g : model.geoms) {
    Range r;
    r.first = static_cast<int>(data.size() / kVertexFloats);
    AppendGeomTriangles(model, g, data);
    r.count = static_cast<int>(data.size() / kVertexFloats) - r.first;
    geoms_.push_back(r);
    if (g.type == GeomType::kPlane) AppendGrid(g, frame, thin, thick);
  }
  thin_lines_ = {static_cast<int>(data.size() / kVertexFloats),
                 static_cast<int>(thin.size() / kVertexFloats)};
  data.insert(data.end(), thin.begin(), thin.end());
  thick_lines_ = {static_cast<int>(data.size() / kVertexFloats),
                  static_cast<int>(thick.size() / kVertexFloats)};
  data.insert(data.end(), thick.begin(), thick.end());

  const unsigned vs = Compile(GL_VERTEX_SHADER, kVertexShader);
  unsigned fs = 0;
  try {
    fs = Compile(GL_FRAGMENT_SHADER, kFragmentShader);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  program_ = glCreateProgram();
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  int ok = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    glDeleteProgram(program_);
    throw Error("view: the geom shaders do not link");
  }
  u_mvp_ = glGetUniformLocation(program_, "mvp");
  u_rot_ = glGetUniformLocation(program_, "rot");
  u_color_ = glGetUniformLocation(program_, "color");
  u_lit_ = glGetUniformLocation(program_, "lit");
  u_light_ = glGetUniformLocation(program_, "light");

  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(),
               GL_STATIC_DRAW);
  const GLsizei stride = kVertexFloats * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

SceneRenderer::~SceneRenderer() {
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void SceneRenderer::Begin(const Camera& cam, double far_m) {
  view_projection_ = cam.ViewProjection(far_m);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glUseProgram(program_);
  glBindVertexArray(vao_);
  // from above, in front and to the left of the scene, fixed in the world
  const Vec3 light = Vec3(0.3, -0.5, 1.0).normalized();
  glUniform3f(u_light_, static_cast<float>(light.x()), static_cast<float>(light.y()),
              static_cast<float>(light.z()));
  glUniform1f(u_lit_, 1.0f);
}

void SceneRenderer::DrawGeom(int g, const Vec3& pos, const Mat3& R, const Rgb& c) {
  const Range& r = geoms_[static_cast<std::size_t>(g)];
  if (r.count == 0) return;
  Eigen::Matrix4f M = Eigen::Matrix4f::Identity();
  M.block<3, 3>(0, 0) = R.cast<float>();
  M.block<3, 1>(0, 3) = pos.cast<float>();
  const Eigen::Matrix4f mvp = Eigen::Map<const Eigen::Matrix4f>(view_projection_.data()) * M;
  const Eigen::Matrix3f rot = R.cast<float>();
  glUniformMatrix4fv(u_mvp_, 1, GL_FALSE, mvp.data());  // Eigen is column-major, as OpenGL
  glUniformMatrix3fv(u_rot_, 1, GL_FALSE, rot.data());
  glUniform3f(u_color_, c[0], c[1], c[2]);
  glDrawArrays(GL_TRIANGLES, r.first, r.count);
}

void SceneRenderer::End(const Rgb& c) {
  glUniformMatrix4fv(u_mvp_, 1, GL_FALSE, view_projection_.data());
  const Eigen::Matrix3f identity = Eigen::Matrix3f::Identity();
  glUniformMatrix3fv(u_rot_, 1, GL_FALSE, identity.data());
  glUniform3f(u_color_, c[0], c[1], c[2]);
  glUniform1f(u_lit_, 0.0f);
  if (thin_lines_.count > 0) glDrawArrays(GL_LINES, thin_lines_.first, thin_lines_.count);
  if (thick_lines_.count > 0) {
    glLineWidth(2.0f);
    glDrawArrays(GL_LINES, thick_lines_.first, thick_lines_.count);
    glLineWidth(1.0f);
  }
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
}

}  // namespace rigidtouch::view
