/* A program that steps through time as a simulation viewer does: every frame the mesh's
 * positions and normals are put into their buffer objects anew (glBufferData; the same mesh,
 * standing in for the next time step's data; with `deform`, its vertices moved along their
 * normals by a wave that travels step by step, as a deforming body's are, worked out before the
 * frame's clock starts), then drawn with glDrawElements and glFinish, with
 * the anchors' camera and light (../shared/anchors/common.h). Prints each frame's time, then a
 * RESULT line (as osmesa_bench's) over frames 1 on: frame 0 is a first frame, the steps after
 * it are what a viewer stepping through time waits for.
 *   gcc -O2 -I../shared/anchors -o steps_bench scripts/steps_bench.c -lOSMesa -lGLU -lpng -lm
 *   ./steps_bench mesh_573.bin 4 [deform]     # llvmpipe
 *   glray run --set preset=gl --set bvh=auto|sah -- ./steps_bench mesh_573.bin 4 */

#define GL_GLEXT_PROTOTYPES
#include "common.h"
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glu.h>
int main(int argc, char **argv) {
  Mesh m; if (argc < 2 || mesh_load(argv[1], &m)) return 1;
  int frames = argc > 2 ? atoi(argv[2]) : 3;
  int deform = argc > 3 && !strcmp(argv[3], "deform");
  float *pos = m.pos;
  if (deform && !(pos = malloc(12 * (size_t)m.nv))) return 1;
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  unsigned char *buf = malloc((size_t)IMG_W * IMG_H * 4);
  OSMesaMakeCurrent(ctx, buf, GL_UNSIGNED_BYTE, IMG_W, IMG_H);
  PFNGLGENBUFFERSPROC genBuffers = (PFNGLGENBUFFERSPROC)OSMesaGetProcAddress("glGenBuffers");
  PFNGLBINDBUFFERPROC bindBuffer = (PFNGLBINDBUFFERPROC)OSMesaGetProcAddress("glBindBuffer");
  PFNGLBUFFERDATAPROC bufferData = (PFNGLBUFFERDATAPROC)OSMesaGetProcAddress("glBufferData");
  glViewport(0, 0, IMG_W, IMG_H);
  glMatrixMode(GL_PROJECTION); gluPerspective(CAM_FOVY_DEG, (double)IMG_W / IMG_H, CAM_NEAR, CAM_FAR);
  glMatrixMode(GL_MODELVIEW);
  gluLookAt(CAM_EYE[0], CAM_EYE[1], CAM_EYE[2], CAM_AT[0], CAM_AT[1], CAM_AT[2], CAM_UP[0], CAM_UP[1], CAM_UP[2]);
  float L[3] = {LIGHT_DIR[0], LIGHT_DIR[1], LIGHT_DIR[2]}; v3norm(L);
  GLfloat lpos[4] = {L[0], L[1], L[2], 0.f}, mat[4] = {0.8f, 0.7f, 0.5f, 1.f};
  glLightfv(GL_LIGHT0, GL_POSITION, lpos);
  glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE, mat);
  glEnable(GL_LIGHTING); glEnable(GL_LIGHT0); glEnable(GL_DEPTH_TEST);
  GLuint vbo[3];
  genBuffers(3, vbo);
  bindBuffer(GL_ELEMENT_ARRAY_BUFFER, vbo[2]);
  bufferData(GL_ELEMENT_ARRAY_BUFFER, 12 * (GLsizeiptr)m.nt, m.idx, GL_STATIC_DRAW);
  glEnableClientState(GL_VERTEX_ARRAY); glEnableClientState(GL_NORMAL_ARRAY);
  double ft[257];
  if (frames < 1) frames = 1;
  if (frames > 256) frames = 256;
  for (int f = 0; f <= frames; f++) {
    /* A wave a hundredth of the mesh's size high (the gyroid spans [-1, 1]). */
    for (uint32_t v = 0; deform && v < m.nv; v++) {
      const float *p = m.pos + 3 * v, *n = m.nrm + 3 * v;
      float a = 0.01f * sinf(4.0f * p[0] + 3.0f * p[1] + 0.5f * (float)f);
      for (int k = 0; k < 3; k++) pos[3 * v + k] = p[k] + a * n[k];
    }
    double t0 = now_s();
    bindBuffer(GL_ARRAY_BUFFER, vbo[0]); bufferData(GL_ARRAY_BUFFER, 12 * (GLsizeiptr)m.nv, pos, GL_DYNAMIC_DRAW);
    glVertexPointer(3, GL_FLOAT, 0, 0);
    bindBuffer(GL_ARRAY_BUFFER, vbo[1]); bufferData(GL_ARRAY_BUFFER, 12 * (GLsizeiptr)m.nv, m.nrm, GL_DYNAMIC_DRAW);
    glNormalPointer(GL_FLOAT, 0, 0);
    bindBuffer(GL_ARRAY_BUFFER, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDrawElements(GL_TRIANGLES, 3 * (GLsizei)m.nt, GL_UNSIGNED_INT, 0);
    glFinish();
    ft[f] = now_s() - t0;
    printf("frame %d %.1f ms\n", f, ft[f] * 1e3);
  }
  printf("RESULT steps tris=%u frames=%d frame_ms_min=%.2f frame_ms_median=%.2f\n", m.nt, frames,
         vmin(ft + 1, frames) * 1e3, median(ft + 1, frames) * 1e3);
  return 0;
}
