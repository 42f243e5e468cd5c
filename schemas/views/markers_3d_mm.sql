-- markers_3d with x, y, z in millimetres, whatever the clip's units.
CREATE OR REPLACE VIEW markers_3d_mm AS
SELECT m.* REPLACE (m.x * s.mm AS x, m.y * s.mm AS y, m.z * s.mm AS z)
FROM markers_3d AS m
JOIN (SELECT clip_id, mm_per_unit(units) AS mm FROM clips) AS s USING (clip_id);
