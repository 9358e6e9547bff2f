"""Parts a workshop can make and a printer can print, from a design.

- :mod:`optim.parts.resolution`: the manufacturing resolution and the rounded design;
- :mod:`optim.parts.options`: the options of the parts (resolution, pin diameter, plate);
- :mod:`optim.parts.joint`: the pivot (pin, boss, common pivot), plate thickness, stacking;
- :mod:`optim.parts.spring`: the spring's free angle and preload, the rest and closing stops;
- :mod:`optim.parts.profile`: each finger's outline in its own frame;
- :mod:`optim.parts.dxf`: one DXF per finger (ezdxf), with its pivot hole, text, dimensions;
- :mod:`optim.parts.mesh`: one 3-D part per finger (an STL through trimesh and manifold3d).
"""
