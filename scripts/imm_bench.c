/* A program that draws a mesh in immediate mode every frame: glBegin(GL_TRIANGLES), glNormal3fv and
 * glVertex3fv per corner, glEnd, glFinish, with the anchors' camera (../shared/anchors/common.h).
 *   gcc -O2 -I../shared/anchors -o imm_bench scripts/imm_bench.c -lOSMesa -lGLU -lpng -lm
 *   ./imm_bench mesh_181.bin 3      # llvmpipe
 *   glray run --set preset=gl --set progressive=false -- ./imm_bench mesh_181.bin 3 */

#include "common.h"
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glu.h>
int main(int argc, char **argv) {
  Mesh m; if (mesh_load(argv[1], &m)) return 1;
  int frames = argc > 2 ? atoi(argv[2]) : 3;
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  unsigned char *buf = malloc((size_t)IMG_W * IMG_H * 4);
  OSMesaMakeCurrent(ctx, buf, GL_UNSIGNED_BYTE, IMG_W, IMG_H);
  glViewport(0, 0, IMG_W, IMG_H);
  glMatrixMode(GL_PROJECTION); gluPerspective(CAM_FOVY_DEG, (double)IMG_W / IMG_H, CAM_NEAR, CAM_FAR);
  glMatrixMode(GL_MODELVIEW);
  gluLookAt(CAM_EYE[0], CAM_EYE[1], CAM_EYE[2], CAM_AT[0], CAM_AT[1], CAM_AT[2], CAM_UP[0], CAM_UP[1], CAM_UP[2]);
  glEnable(GL_LIGHTING); glEnable(GL_LIGHT0); glEnable(GL_DEPTH_TEST);
  for (int f = 0; f <= frames; f++) {
    double t0 = now_s();
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glBegin(GL_TRIANGLES);
    for (size_t i = 0; i < 3 * (size_t)m.nt; i++) { uint32_t v = m.idx[i]; glNormal3fv(m.nrm + 3 * (size_t)v); glVertex3fv(m.pos + 3 * (size_t)v); }
    glEnd();
    glFinish();
    printf("frame %d %.1f ms\n", f, (now_s() - t0) * 1e3);
  }
  return 0;
}
