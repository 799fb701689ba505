// SPDX-License-Identifier: GPL-3.0-or-later
// What every kernel shares: 64 invocations per workgroup; the invocation's index over a grid of
// rows of at most 65535 workgroups (Commands::dispatch); storage bindings of 32-bit words, int8
// and uint8 tables read from them.
#ifndef TEXFAB_DISPATCH_GLSL
#define TEXFAB_DISPATCH_GLSL

#extension GL_EXT_shader_explicit_arithmetic_types_int32 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(local_size_x = 64) in;

uint invocationIndex() {
  return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationID.x;
}

// Binding b of set 0 as `name.words[]`; the array forms as `name[n].words[]`.
#define WORDS(b, name) layout(set = 0, binding = b) buffer name##Block { uint words[]; } name
#define READ_WORDS(b, name) layout(set = 0, binding = b) readonly buffer name##Block { uint words[]; } name
#define READ_WORD_ARRAYS(b, name, n) layout(set = 0, binding = b) readonly buffer name##Block { uint words[]; } name[n]

// Byte i of a word binding, as a signed or unsigned 8-bit value (tables of bytes, little-endian).
#define INT8_AT(buf, i) bitfieldExtract(int((buf).words[(i) >> 2]), int(((i) & 3u) * 8u), 8)
#define UINT8_AT(buf, i) bitfieldExtract((buf).words[(i) >> 2], int(((i) & 3u) * 8u), 8)

// Squared distance of the 4 signed bytes of two words.
int ssd4(uint a, uint b) {
  int s = 0;
  for (int i = 0; i < 32; i += 8) {
    const int d = bitfieldExtract(int(a), i, 8) - bitfieldExtract(int(b), i, 8);
    s += d * d;
  }
  return s;
}

#endif
