-- truth_3d with x, y, z in millimetres, whatever the clip's units.
CREATE OR REPLACE VIEW truth_3d_mm AS
SELECT t.* REPLACE (t.x * s.mm AS x, t.y * s.mm AS y, t.z * s.mm AS z)
FROM truth_3d AS t
JOIN (SELECT clip_id, mm_per_unit(units) AS mm FROM clips) AS s USING (clip_id);
