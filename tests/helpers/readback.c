/* An OSMesa program that draws one lit-free, smooth-shaded triangle with depth testing and reads
 * the frame back with glReadPixels as DEPTH_COMPONENT (float and unsigned int) and RGB bytes,
 * printing a few pixels: under glray the read must return the ray-traced frame, with Mesa's
 * depth values.
 *
 * Between the draw and the reads (where glray presents its frame) it sets, on purpose, the state
 * a present must not be disturbed by or disturb: a bound GLSL program, vertex array, textures on
 * units 0 and 1 and a sampler, an unpack buffer and unpack layout, viewport, scissor, blending,
 * masks, depth function, culling, polygon modes, alpha test. After the reads it prints that
 * state and glGetError: it must read the same with and without glray, whichever way glray
 * presents (GLRAY_PRESENT). Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

static void print_ints(const char *what, GLenum pname, int n) {
  GLint v[4] = {0};
  glGetIntegerv(pname, v);
  printf("%s", what);
  for (int i = 0; i < n; i++) printf(" %d", v[i]);
  printf("\n");
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  osmesa_context(w, h, &buf);
  load_gl_functions();
  printf("version %s\n", (const char *)glGetString(GL_VERSION));

  glViewport(0, 0, w, h);
  glMatrixMode(GL_PROJECTION); glLoadIdentity(); glFrustum(-1, 1, -1, 1, 1, 10);
  glMatrixMode(GL_MODELVIEW); glLoadIdentity();
  glEnable(GL_DEPTH_TEST);
  glClearColor(0.1, 0.2, 0.3, 1); glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glBegin(GL_TRIANGLES);
  glColor3f(1, 0, 0); glVertex3f(-2, -2, -3); glColor3f(0, 1, 0); glVertex3f(2, -2, -5); glColor3f(0, 0, 1); glVertex3f(0, 2, -4);
  glEnd();

  /* The state a present must leave alone. */
  const char *vs = "#version 120\nvoid main() { gl_Position = gl_Vertex; }\n";
  const char *fs = "#version 120\nvoid main() { gl_FragColor = vec4(1.0); }\n";
  GLuint prog = program_of(vs, fs);
  glUseProgram(prog);
  GLuint vao, tex[2], sampler, pbo;
  glGenVertexArrays(1, &vao); glBindVertexArray(vao);
  glGenTextures(2, tex);
  glActiveTexture(GL_TEXTURE0); glBindTexture(GL_TEXTURE_2D, tex[0]);
  glActiveTexture(GL_TEXTURE1); glBindTexture(GL_TEXTURE_2D, tex[1]);
  glGenSamplers(1, &sampler); glBindSampler(1, sampler);
  glActiveTexture(GL_TEXTURE3);
  glGenBuffers(1, &pbo); glBindBuffer(GL_PIXEL_UNPACK_BUFFER, pbo);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 2); glPixelStorei(GL_UNPACK_ROW_LENGTH, 7);
  glViewport(3, 4, 50, 40);
  glEnable(GL_SCISSOR_TEST); glScissor(1, 2, 10, 11);
  glEnable(GL_BLEND); glEnable(GL_CULL_FACE); glEnable(GL_ALPHA_TEST);
  glColorMask(GL_TRUE, GL_FALSE, GL_TRUE, GL_FALSE);
  glDepthFunc(GL_GREATER); glDepthMask(GL_FALSE);
  glPolygonMode(GL_FRONT, GL_LINE); glPolygonMode(GL_BACK, GL_POINT);

  float depth[64 * 64]; unsigned char rgb[64 * 64 * 3]; unsigned int udepth[64 * 64];
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
  glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, udepth);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb);
  int pts[][2] = {{32, 32}, {10, 10}, {50, 20}, {32, 50}, {0, 63}};
  for (int i = 0; i < 5; i++) {
    int x = pts[i][0], y = pts[i][1], k = y * w + x;
    printf("(%d,%d) depth %.5f u %u rgb %d %d %d\n", x, y, depth[k], udepth[k] >> 16, rgb[3*k], rgb[3*k+1], rgb[3*k+2]);
  }

  /* The whole frame, for comparing the ways glray presents (edge pixels differ from Mesa's). */
  unsigned long long hash = 1469598103934665603ull;
  for (int k = 0; k < w * h * 3; k++) hash = (hash ^ rgb[k]) * 1099511628211ull;
  for (int k = 0; k < w * h; k++) hash = (hash ^ udepth[k]) * 1099511628211ull;
  printf("frame hash %016llx\n", hash);

  GLint program = 0, array = 0;
  glGetIntegerv(GL_CURRENT_PROGRAM, &program); glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &array);
  printf("program bound %d vertex array bound %d\n", program == (GLint)prog, array == (GLint)vao);
  print_ints("active texture", GL_ACTIVE_TEXTURE, 1);
  for (int unit = 0; unit < 2; unit++) {
    glActiveTexture(GL_TEXTURE0 + unit);
    print_ints("unit texture", GL_TEXTURE_BINDING_2D, 1);
    print_ints("unit sampler", GL_SAMPLER_BINDING, 1);
  }
  glActiveTexture(GL_TEXTURE3);
  print_ints("unpack buffer", GL_PIXEL_UNPACK_BUFFER_BINDING, 1);
  print_ints("unpack alignment", GL_UNPACK_ALIGNMENT, 1);
  print_ints("unpack row length", GL_UNPACK_ROW_LENGTH, 1);
  print_ints("viewport", GL_VIEWPORT, 4);
  print_ints("scissor box", GL_SCISSOR_BOX, 4);
  print_ints("colour mask", GL_COLOR_WRITEMASK, 4);
  print_ints("depth func", GL_DEPTH_FUNC, 1);
  print_ints("depth mask", GL_DEPTH_WRITEMASK, 1);
  print_ints("polygon mode", GL_POLYGON_MODE, 2);
  GLenum caps[] = {GL_SCISSOR_TEST, GL_BLEND, GL_CULL_FACE, GL_ALPHA_TEST, GL_DEPTH_TEST, GL_STENCIL_TEST,
                   GL_TEXTURE_2D, GL_LIGHTING, GL_FOG, GL_POLYGON_OFFSET_FILL, GL_FRAMEBUFFER_SRGB};
  printf("enabled");
  for (unsigned i = 0; i < sizeof caps / sizeof caps[0]; i++) printf(" %d", glIsEnabled(caps[i]));
  printf("\nerror 0x%x\n", glGetError());
  return 0;
}
