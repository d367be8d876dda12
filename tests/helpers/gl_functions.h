/* What the OSMesa test helpers share: a compatibility context current on a w x h RGBA buffer,
 * a projection in window coordinates, a square, the GL 2.0-3.3 functions they call, looked up
 * with OSMesaGetProcAddress (libOSMesa need not export them), and a GLSL program made from two
 * sources. Included by every OSMesa helper here; those calling GL 2.0-3.3 functions call
 * load_gl_functions() once a context is current. */
#ifndef GLRAY_TEST_GL_FUNCTIONS_H
#define GLRAY_TEST_GL_FUNCTIONS_H
#define GL_GLEXT_PROTOTYPES
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <stdio.h>
#include <stdlib.h>

#define GL_FUNCTIONS(X)                                                                          \
  X(PFNGLCREATESHADERPROC, glCreateShader)                                                       \
  X(PFNGLSHADERSOURCEPROC, glShaderSource)                                                       \
  X(PFNGLCOMPILESHADERPROC, glCompileShader)                                                     \
  X(PFNGLCREATEPROGRAMPROC, glCreateProgram)                                                     \
  X(PFNGLATTACHSHADERPROC, glAttachShader)                                                       \
  X(PFNGLLINKPROGRAMPROC, glLinkProgram)                                                         \
  X(PFNGLUSEPROGRAMPROC, glUseProgram)                                                           \
  X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays)                                                 \
  X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)                                                 \
  X(PFNGLGENBUFFERSPROC, glGenBuffers)                                                           \
  X(PFNGLBINDBUFFERPROC, glBindBuffer)                                                           \
  X(PFNGLBUFFERDATAPROC, glBufferData)                                                           \
  X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)                                         \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)                                 \
  X(PFNGLACTIVETEXTUREPROC, glActiveTexture)                                                     \
  X(PFNGLGENSAMPLERSPROC, glGenSamplers)                                                         \
  X(PFNGLBINDSAMPLERPROC, glBindSampler)

/* Pointers named p_glX, called through the usual names. */
#define DECLARE(type, name) static type p_##name;
GL_FUNCTIONS(DECLARE)
#undef DECLARE
#define glCreateShader p_glCreateShader
#define glShaderSource p_glShaderSource
#define glCompileShader p_glCompileShader
#define glCreateProgram p_glCreateProgram
#define glAttachShader p_glAttachShader
#define glLinkProgram p_glLinkProgram
#define glUseProgram p_glUseProgram
#define glGenVertexArrays p_glGenVertexArrays
#define glBindVertexArray p_glBindVertexArray
#define glGenBuffers p_glGenBuffers
#define glBindBuffer p_glBindBuffer
#define glBufferData p_glBufferData
#define glVertexAttribPointer p_glVertexAttribPointer
#define glEnableVertexAttribArray p_glEnableVertexAttribArray
#define glActiveTexture p_glActiveTexture
#define glGenSamplers p_glGenSamplers
#define glBindSampler p_glBindSampler

/* A compatibility context (24-bit depth) made current on a new w x h RGBA byte buffer, stored
 * in *buf; the program exits with status 1 if OSMesa gives none. */
static OSMesaContext osmesa_context(int w, int h, unsigned char **buf) {
  OSMesaContext c = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  *buf = malloc((size_t)w * h * 4);
  if (!c || !*buf || !OSMesaMakeCurrent(c, *buf, GL_UNSIGNED_BYTE, w, h)) {
    fprintf(stderr, "no OSMesa context\n");
    exit(1);
  }
  return c;
}

/* A projection that makes vertex (x, y) the window position (x, y) of a w x h window: one unit
 * a pixel, the origin at the bottom left corner. */
static inline void window_projection(int w, int h) {
  glMatrixMode(GL_PROJECTION);
  glOrtho(0, w, 0, h, -1, 1);
  glMatrixMode(GL_MODELVIEW);
}

/* A square 2 * half across in the plane z, facing +z (immediate mode). */
static inline void square(float half, float z) {
  glBegin(GL_QUADS);
  glVertex3f(-half, -half, z);
  glVertex3f(half, -half, z);
  glVertex3f(half, half, z);
  glVertex3f(-half, half, z);
  glEnd();
}

static void load_gl_functions(void) {
#define LOAD(type, name) p_##name = (type)OSMesaGetProcAddress(#name);
  GL_FUNCTIONS(LOAD)
#undef LOAD
}

/* A linked program of a vertex and a fragment shader. */
static GLuint program_of(const char *vs, const char *fs) {
  GLuint s1 = glCreateShader(GL_VERTEX_SHADER), s2 = glCreateShader(GL_FRAGMENT_SHADER);
  glShaderSource(s1, 1, &vs, NULL);
  glCompileShader(s1);
  glShaderSource(s2, 1, &fs, NULL);
  glCompileShader(s2);
  GLuint prog = glCreateProgram();
  glAttachShader(prog, s1);
  glAttachShader(prog, s2);
  glLinkProgram(prog);
  return prog;
}
#endif
