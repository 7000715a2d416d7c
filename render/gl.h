// Picks the GL headers: GLES 3.0 under Emscripten (WebGL2), desktop GL with
// prototypes natively (OSMesa exports every entry point we use). The renderer
// only calls functions that exist in GLES 3.0, so both builds share its code.
#pragma once
#ifdef __EMSCRIPTEN__
#include <GLES3/gl3.h>
#else
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES
#endif
#include <GL/gl.h>
#include <GL/glext.h>
#endif
