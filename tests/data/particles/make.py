"""Blender particles baked to Alembic, as an animator's leaf-particle cache
reaches leafmagic: the oracle for reading Alembic `Points`
(tests/integration/particles.rs).

    python make.py     # leaves.abc, dying.abc and their .blender.csv

(bpy 5.0.1, pip install bpy.) A 20 cm plane 1 m up, its normal tilted, emits
particles in a 24 fps shot of 36 frames: Newtonian
physics with air drag and Brownian motion, so their paths sway. Particle
size 5 cm, scaled randomly by up to 50 % (Blender writes it as each
point's width). The plane's object moves and turns, so the points are
written in its frame under a moving Xform.

- `leaves.abc`: 6 particles emitted over frames 1-10, lifetime 100 frames,
  so none dies during the shot; Blender's exporter (default options, y up)
  writes each living particle with its place in the list as `.pointIds`,
  which is its own number while none has died.
- `dying.abc`: 12 particles emitted over frames 1-24, each living 12
  frames less up to 60 % at random, so they die out of the order they
  were born in, some in the very frame another is born, and the exporter
  renumbers the rest each time.

Beside each, `.blender.csv`: every living particle at every frame as
Blender's particle system holds it, by its own index, world metres, z up:
frame, particle, x, y, z, size.
"""
import bpy, csv


def shot(count, last, lifetime, spread=0.0):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 36
    sc.render.fps = 24
    bpy.ops.mesh.primitive_plane_add(size=0.2, location=(0.1, -0.2, 1.0))
    em = bpy.context.active_object
    em.name = "tree"
    em.rotation_euler = (0.3, 0.0, 0.5)
    em.keyframe_insert("location", frame=1)
    em.keyframe_insert("rotation_euler", frame=1)
    em.location = (0.3, -0.1, 1.1)
    em.rotation_euler = (0.2, 0.1, 0.9)
    em.keyframe_insert("location", frame=36)
    em.keyframe_insert("rotation_euler", frame=36)
    ps = em.modifiers.new("leaves", "PARTICLE_SYSTEM").particle_system
    ps.seed = 7
    st = ps.settings
    st.count = count
    st.frame_start, st.frame_end = 1, last
    st.lifetime = lifetime
    st.lifetime_random = spread
    st.normal_factor = 0.2
    st.particle_size = 0.05
    st.size_random = 0.5
    st.drag_factor = 0.6
    st.brownian_factor = 2.0
    st.render_type = "NONE"
    for f in range(1, 37):
        sc.frame_set(f)
    return sc, em


for name, count, last, lifetime, spread in [
    ("leaves", 6, 10, 100, 0.0),
    ("dying", 12, 24, 12, 0.6),
]:
    sc, em = shot(count, last, lifetime, spread)
    with open(name + ".blender.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "particle", "x", "y", "z", "size"])
        for k in range(1, 37):
            sc.frame_set(k)
            dg = bpy.context.evaluated_depsgraph_get()
            for i, p in enumerate(em.evaluated_get(dg).particle_systems[0].particles):
                if p.alive_state == "ALIVE":
                    w.writerow([k, i] + ["%.7g" % c for c in p.location] + ["%.7g" % p.size])
    bpy.ops.wm.alembic_export(
        filepath=name + ".abc", start=1, end=36, export_particles=True, export_hair=False
    )
