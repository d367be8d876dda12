/* An OSMesa program whose first frame (one red triangle over a blue clear, ended by glFinish)
 * counts, with an occlusion query, the samples the real GL rasterized for it, then prints the
 * count and the colour at the middle of the buffer. Under glray the triangle is ray traced and
 * put in place: by default the real GL rasterizes nothing (every way an OSMesa program sees its
 * pixels ends a frame, so draws are skipped from the first frame on), and the pixel is red all
 * the same.
 *
 * `first_frame mixed`: three frames, each the triangle and, drawn with a GLSL program, a green
 * square at the bottom left; after each it prints the middle and the square's colours. glray
 * leaves frames with shader draws to the real GL; the first one's triangle, not rasterized,
 * is lost, and the frames after it must be the real GL's in full. Built by tests/raytrace.rs
 * with cc. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_functions.h"

static void red_triangle(void) {
  glColor3f(1, 0, 0);
  glBegin(GL_TRIANGLES);
  glVertex2f(-0.9f, -0.9f);
  glVertex2f(0.9f, -0.9f);
  glVertex2f(0.0f, 0.9f);
  glEnd();
}

static void mixed(const unsigned char *buf, int w, int h) {
  load_gl_functions();
  const char *vs = "#version 120\nvoid main() { gl_Position = gl_Vertex; }\n";
  const char *fs = "#version 120\nvoid main() { gl_FragColor = vec4(0.0, 1.0, 0.0, 1.0); }\n";
  GLuint prog = program_of(vs, fs);
  for (int frame = 0; frame < 3; frame++) {
    glClear(GL_COLOR_BUFFER_BIT);
    red_triangle();
    glUseProgram(prog);
    glRectf(-1.0f, -1.0f, -0.8f, -0.8f);
    glUseProgram(0);
    glFinish();
    const unsigned char *m = buf + 4 * (w * (h / 2) + w / 2), *q = buf + 4 * (w * 1 + 1);
    printf("frame %d middle %d %d %d square %d %d %d\n", frame, m[0], m[1], m[2], q[0], q[1], q[2]);
  }
}

int main(int argc, char **argv) {
  int w = 32, h = 32;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  if (argc > 1 && strcmp(argv[1], "mixed") == 0) {
    glViewport(0, 0, w, h);
    glClearColor(0, 0, 1, 1);
    mixed(buf, w, h);
    OSMesaDestroyContext(c);
    free(buf);
    return 0;
  }
  PFNGLGENQUERIESPROC gen = (PFNGLGENQUERIESPROC)OSMesaGetProcAddress("glGenQueries");
  PFNGLBEGINQUERYPROC begin = (PFNGLBEGINQUERYPROC)OSMesaGetProcAddress("glBeginQuery");
  PFNGLENDQUERYPROC end = (PFNGLENDQUERYPROC)OSMesaGetProcAddress("glEndQuery");
  PFNGLGETQUERYOBJECTUIVPROC result = (PFNGLGETQUERYOBJECTUIVPROC)OSMesaGetProcAddress("glGetQueryObjectuiv");
  GLuint query;
  gen(1, &query);
  glViewport(0, 0, w, h);
  glClearColor(0, 0, 1, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  begin(GL_SAMPLES_PASSED, query);
  red_triangle();
  end(GL_SAMPLES_PASSED);
  glFinish();
  GLuint samples = 0;
  result(query, GL_QUERY_RESULT, &samples);
  const unsigned char *p = buf + 4 * (w * (h / 2) + w / 2);
  printf("rasterized %u\nmiddle %d %d %d\n", samples, p[0], p[1], p[2]);
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
