-- validation_joint with its depth and position errors in millimetres (units = 'mm').
CREATE OR REPLACE VIEW validation_joint_mm AS
SELECT * REPLACE (
    dz_min * mm_per_unit(units) AS dz_min,
    dz_max * mm_per_unit(units) AS dz_max,
    dz_mean * mm_per_unit(units) AS dz_mean,
    dz_std * mm_per_unit(units) AS dz_std,
    mpjpe * mm_per_unit(units) AS mpjpe,
    'mm' AS units)
FROM validation_joint;
