"""rbcd-gl2rbt: a captured OpenGL stream (apitrace) into the unit's input.

    rbcd-gl2rbt TRACE -o OUT.rbt[.zst] [--geometry OUT.geo] [--frames A:B] [--screen W H]
                [--select RULES.toml] [--depth-bits N] [--tile W H] [--summary FILE]
    rbcd-gl2rbt TRACE --list-draws FRAME [--image OUT.png] [--select RULES.toml]
    rbcd-gl2rbt TRACE --check-depth [--frames A:B]          agreement with Mesa (glretrace -D)

The capture is read through apitrace's own reader (`apitrace pickle`), call by
call, one frame at a time; this program emulates the GL state that decides
where fragments land (docs/gl-capture.md lists it) and hands each frame's draws
to rbcd-gl-raster, which rasterizes them through the scene front end's tile
rasterizer and writes the trace. A frame ends at each buffer swap.

Which draws are collisionable: a draw inside a KHR_debug group
glPushDebugGroup(GL_DEBUG_SOURCE_APPLICATION, N, -1, "rbcd-object") belongs to
object N, as does one inside an EXT_debug_marker group "rbcd-object N" (the
innermost counts); or, for unmodified programs, a selection file (--select)
of rules. Everything else is the GPU's other work.

Exit status: 0 done; 2 bad capture, call, selection file or command line (one
line on stderr naming the capture and call number, no output left); 1 a tool
failed. Needs apitrace, numpy and the OpenGL registry (khronos-api): scripts/setup.sh --gl.

The package, by concern:

    cli            the command line and its exit statuses
    capture        the capture, apitrace's or reduced; apitrace: apitrace's reader
    reduced        the reduced capture's format, read and written
    converter      the emulation: the GL state, call by call, into draw records
    gl_registry    GL's functions and enumerants (Khronos' gl.xml) as apitrace writes them
    glstate/       the GL state by state group, with its calls' handlers
    glmath         fixed-function matrices and primitive assembly
    selection      selection files; entities: the objects of unmodified games
    geometry       each frame's collisionable geometry for rbcd-cpucd
    raster         the raster driver (rbcd-gl-raster) and the run's report
    listing        --list-draws; depth_check: --check-depth against Mesa
    outputs        streamed outputs; errors: the converter's errors
"""
