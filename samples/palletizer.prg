%%%
  VERSION:1
  LANGUAGE:ENGLISH
%%%

MODULE Palletizer
  ! Stack boxes in a 3 x 4 grid, five layers; place positions are computed
  ! from one taught corner target, so they are known only at run time.
  PERS tooldata tVacuum:=[TRUE,[[0,0,220],[1,0,0,0]],[6.5,[0,0,95],[1,0,0,0],0.1,0.1,0.05]];
  PERS wobjdata wPallet:=[FALSE,TRUE,"",[[300,900,-85],[0.7071068,0,0,-0.7071068]],[[0,0,0],[1,0,0,0]]];
  CONST robtarget pPickBox:=[[1180,-95.5,640],[0,0,1,0],[-1,0,-1,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  PERS robtarget pCorner:=[[150,100,0],[0,0.7071068,0.7071068,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  VAR robtarget pPlace;
  CONST num nBoxX:=300;
  CONST num nBoxY:=200;
  CONST num nBoxZ:=0.15E+03;
  VAR num nLayer;
  VAR num nRow;
  VAR num nCol;

  PROC main()
    FOR nLayer FROM 0 TO 4 DO
      FOR nRow FROM 0 TO 2 DO
        FOR nCol FROM 0 TO 3 DO
          MoveJ Offs(pPickBox, 0, 0, 200), v2000, z50, tVacuum;
          MoveL pPickBox, v500, fine, tVacuum;
          PulseDO \PLength:=0.2, doVacuumOn;
          MoveL Offs(pPickBox, 0, 0, 200), v2000, z50, tVacuum;
          pPlace := Offs(pCorner, nRow * nBoxX, nCol * nBoxY, (nLayer + 1) * nBoxZ);
          MoveJ Offs(pPlace, 0, 0, 150), v2000, z50, tVacuum\WObj:=wPallet;
          MoveL pPlace, v300, fine, tVacuum\WObj:=wPallet;
          PulseDO \PLength:=0.2, doVacuumOff;
          MoveL Offs(pPlace, 0, 0, 150), v2000, z50, tVacuum\WObj:=wPallet;
        ENDFOR
      ENDFOR
    ENDFOR
  ENDPROC
ENDMODULE
