"""Lights and environment: clustered light lists, the light rows, deferred lighting, the
environment map (its CPU cube maths, GGX prefilter and Radiance .hdr reader)."""
