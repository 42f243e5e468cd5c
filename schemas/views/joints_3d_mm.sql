-- joints_3d with every length in millimetres, whatever the clip's units (scale: pixels per mm).
CREATE OR REPLACE VIEW joints_3d_mm AS
SELECT j.* REPLACE (
    j.x * s.mm AS x,
    j.y * s.mm AS y,
    j.z * s.mm AS z,
    j.scale / s.mm AS scale,
    j.length_inconsistency * s.mm AS length_inconsistency,
    j.residual * s.mm AS residual)
FROM joints_3d AS j
JOIN (SELECT clip_id, mm_per_unit(units) AS mm FROM clips) AS s USING (clip_id);
