/* An OSMesa program in a core profile (GL 3.3 core): it calls fixed-function glBegin/glEnd,
 * which a core profile refuses (GL_INVALID_OPERATION, nothing drawn), then draws a triangle the
 * core way (GLSL program, vertex array, buffer) and reads the frame back. Under glray the output
 * must be the same as without: glray captures fixed-function GL only, so a core profile's frames
 * stay the real GL's. Built by tests/raytrace.rs with cc. */
#include <stdio.h>
#include <stdlib.h>

#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                   OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
  OSMesaContext c = OSMesaCreateContextAttribs(attribs, NULL);
  if (!c) { printf("no core profile context\n"); return 1; }
  void *buf = malloc(w * h * 4);
  OSMesaMakeCurrent(c, buf, GL_UNSIGNED_BYTE, w, h);
  load_gl_functions();
  printf("version %s\n", (const char *)glGetString(GL_VERSION));

  glViewport(0, 0, w, h);
  glClearColor(0.1, 0.2, 0.3, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  /* Fixed function: refused by a core profile. */
  glBegin(GL_TRIANGLES); glVertex3f(-1, -1, 0); glVertex3f(1, -1, 0); glVertex3f(0, 1, 0); glEnd();
  printf("glBegin error 0x%x\n", glGetError());

  /* The core way. */
  const char *vs = "#version 330 core\nlayout(location = 0) in vec2 p;\nvoid main() { gl_Position = vec4(p, 0.0, 1.0); }\n";
  const char *fs = "#version 330 core\nout vec4 c;\nvoid main() { c = vec4(0.9, 0.5, 0.1, 1.0); }\n";
  GLuint prog = program_of(vs, fs);
  float tri[] = {-0.8f, -0.8f, 0.8f, -0.8f, 0.0f, 0.6f};
  GLuint vao, vbo;
  glGenVertexArrays(1, &vao); glBindVertexArray(vao);
  glGenBuffers(1, &vbo); glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, sizeof tri, tri, GL_STATIC_DRAW);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, 0); glEnableVertexAttribArray(0);
  glUseProgram(prog);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  printf("draw error 0x%x\n", glGetError());

  unsigned char rgba[64 * 64 * 4];
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
  int k = (20 * w + 32) * 4, e = (60 * w + 2) * 4;
  printf("inside %d %d %d, outside %d %d %d\n", rgba[k], rgba[k + 1], rgba[k + 2], rgba[e], rgba[e + 1], rgba[e + 2]);
  unsigned long long hash = 1469598103934665603ull;
  for (int i = 0; i < w * h * 4; i++) hash = (hash ^ rgba[i]) * 1099511628211ull;
  printf("frame hash %016llx error 0x%x\n", hash, glGetError());
  return 0;
}
